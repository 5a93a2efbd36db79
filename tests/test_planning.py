"""cp.plan: the plan inferred for a table of scenes, and every refusal of an override.

The plan names every slot (normal, tangential, coupling, memory); "none" is a model. The
Dundurs β of a pair vanishes (no normal-tangential coupling) for identical bodies, for two
incompressible (or rigid) bodies, and for a rigid body on an incompressible one.
"""
import pytest
from helpers import MU, STEEL, W, fretting_scene, make_scene

import contactpipe as cp
from contactpipe.planning import RULES, Rule, models, pair_couples

RIGID = {"material": "rigid"}
ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}
INCOMPRESSIBLE = {"material": "elastic", "young": 210e9, "poisson": 0.5}
RUBBER = {"material": "elastic", "young": 5e9, "poisson": 0.5}
MAXWELL = {"material": "viscoelastic", "young": 105e9, "poisson": 0.3, "creep": "maxwell",
           "relaxation_time": 1.0}
MAXWELL_SLOW = {**MAXWELL, "relaxation_time": 2.0}
TABULATED = {"material": "viscoelastic", "young": 105e9, "poisson": 0.3, "creep": "tabulated",
             "table": [[0.0, 1.0], [1.0, 2.0], [2.0, 2.5]]}

T_X1 = [0.0, 0.5 * MU * W]
T_X2 = [[0.0, 0.0], [0.3 * MU * W, 0.4 * MU * W]]


FRICTIONLESS = {"preload": "frictionless"}


def scene(indenter=STEEL, halfspace=STEEL, mu=MU, T=T_X1, steps=2, load_keys=None, **over):
    load = {"time": [0.0, 1.0], "normal_force": W, **(load_keys or {})}
    if T is not None:
        load["tangential_force"] = T
    if RUBBER in (indenter, halfspace):   # its contact outgrows the grid sized for steel
        over.setdefault("grid", {"size": "auto"})
    return make_scene(indenter=dict(indenter), halfspace=dict(halfspace),
                      friction={"mu": mu}, load=load, time={"steps": steps}, **over)


# (id, scene keywords, expected (tangential, coupling, memory))
TABLE = [
    ("steel pair, T1", {}, ("scalar", "none", "none")),
    ("steel pair, T2", {"T": T_X2}, ("vector", "none", "none")),
    ("steel pair, no T", {"T": None}, ("none", "none", "none")),
    # a coupled pair pressed with friction: Spence's radial shear, q2 as large as q1
    ("steel on aluminium, T1", {"halfspace": ALUMINIUM}, ("vector", "gauss_seidel", "none")),
    ("steel on aluminium, T2", {"halfspace": ALUMINIUM, "T": T_X2},
     ("vector", "gauss_seidel", "none")),
    ("steel on aluminium, no T", {"halfspace": ALUMINIUM, "T": None},
     ("vector", "gauss_seidel", "none")),
    # pressed without friction and held: q2 only from K21 and K23 (Cattaneo-Mindlin)
    ("steel on aluminium, T1, frictionless preload",
     {"halfspace": ALUMINIUM, "load_keys": FRICTIONLESS}, ("scalar", "gauss_seidel", "none")),
    ("steel on aluminium, no T, frictionless preload",
     {"halfspace": ALUMINIUM, "T": None, "load_keys": FRICTIONLESS},
     ("scalar", "gauss_seidel", "none")),
    ("steel on aluminium, frictionless preload, W varies",
     {"halfspace": ALUMINIUM, "load_keys": {**FRICTIONLESS, "normal_force": [W, 2 * W]}},
     ("vector", "gauss_seidel", "none")),
    ("steel on aluminium, frictionless preload, M2 varies",
     {"halfspace": ALUMINIUM, "load_keys": {**FRICTIONLESS, "moment2": [0.0, 1e-4 * W]}},
     ("vector", "gauss_seidel", "none")),
    ("steel pair, frictionless preload, W varies",
     {"load_keys": {**FRICTIONLESS, "normal_force": [W, 2 * W]}}, ("scalar", "none", "none")),
    ("steel pair, T1, tilt about x1", {"load_keys": {"moment1": 1e-4 * W}},
     ("vector", "none", "none")),
    ("steel pair, T1, tilt about x2", {"load_keys": {"moment2": 1e-4 * W}},
     ("scalar", "none", "none")),
    ("steel on aluminium, mu = 0", {"halfspace": ALUMINIUM, "T": None, "mu": 0.0},
     ("none", "none", "none")),
    ("two incompressible, different E", {"indenter": INCOMPRESSIBLE, "halfspace": RUBBER},
     ("scalar", "none", "none")),
    ("rigid on incompressible", {"indenter": RIGID, "halfspace": RUBBER},
     ("scalar", "none", "none")),
    ("rigid on incompressible, no T", {"indenter": RIGID, "halfspace": RUBBER, "T": None},
     ("none", "none", "none")),
    ("rigid on steel", {"indenter": RIGID}, ("vector", "gauss_seidel", "none")),
    ("rigid on steel, frictionless preload", {"indenter": RIGID, "load_keys": FRICTIONLESS},
     ("scalar", "gauss_seidel", "none")),
    # a coupled viscoelastic pair: the pressure and the coupling creep under a held load
    ("rigid on Maxwell (the paper)", {"indenter": RIGID, "halfspace": MAXWELL},
     ("vector", "gauss_seidel", "recursive")),
    ("rigid on Maxwell, frictionless preload",
     {"indenter": RIGID, "halfspace": MAXWELL, "load_keys": FRICTIONLESS},
     ("vector", "gauss_seidel", "recursive")),
    ("rigid on Maxwell, mu = 0", {"indenter": RIGID, "halfspace": MAXWELL, "T": None,
                                  "mu": 0.0}, ("none", "none", "recursive")),
    ("identical Maxwell pair", {"indenter": MAXWELL, "halfspace": MAXWELL},
     ("scalar", "none", "recursive")),
    ("Maxwell pair, different relaxation times",
     {"indenter": MAXWELL, "halfspace": MAXWELL_SLOW}, ("vector", "gauss_seidel", "recursive")),
    ("rigid on tabulated creep", {"indenter": RIGID, "halfspace": TABULATED},
     ("vector", "gauss_seidel", "direct")),
    ("Maxwell on tabulated", {"indenter": MAXWELL, "halfspace": TABULATED},
     ("vector", "gauss_seidel", "direct")),
]


@pytest.mark.parametrize("kw, expected", [pytest.param(kw, e, id=i) for i, kw, e in TABLE])
def test_inferred_plan(kw, expected):
    """The inferred (tangential, coupling, memory) of each scene of the table; normal is
    always Polonsky-Keer, and describe() names the slots that run."""
    sc = scene(**kw)
    pl = cp.plan(sc)
    assert (pl.tangential, pl.coupling, pl.memory) == expected
    assert pl.normal == "polonsky_keer"
    text = pl.describe()
    assert text.startswith(f"normal=polonsky_keer, tangential={expected[0]}, "
                           f"coupling={expected[1]}, memory={expected[2]}")
    assert ("time_rule=" in text) == (expected[2] != "none")
    assert ("preload=" in text) == (expected[0] != "none")
    assert pl.as_dict()["tangential"] == expected[0]


@pytest.mark.parametrize("indenter, halfspace, couples", [
    (STEEL, STEEL, False), (STEEL, ALUMINIUM, True), (INCOMPRESSIBLE, RUBBER, False),
    (RIGID, RUBBER, False), (RIGID, STEEL, True), (MAXWELL, MAXWELL, False),
    (MAXWELL, MAXWELL_SLOW, True), (RIGID, MAXWELL, True),
])
def test_pair_couples_is_symmetric(indenter, halfspace, couples):
    """β = 0 cases (identical bodies, both incompressible, rigid on incompressible) do not
    couple, whichever body is the indenter."""
    sc = scene(indenter=indenter, halfspace=halfspace)
    b1, b2 = sc.indenter.body(), sc.halfspace.body()
    assert pair_couples(b1, b2) is couples
    assert pair_couples(b2, b1) is couples


def test_single_instant_has_no_memory():
    """One instant (load.time = [0]): no history to remember, even on a Maxwell body."""
    sc = make_scene(indenter=dict(RIGID), halfspace=dict(MAXWELL),
                    load={"time": [0.0], "normal_force": W}, time=None)
    assert cp.plan(sc).memory == "none"


def test_time_rule_and_preload_are_recorded():
    sc = make_scene(indenter=dict(RIGID), halfspace=dict(MAXWELL), friction={"mu": MU},
                    solver={"time_rule": "step_start"}, time={"steps": 2},
                    load={"time": [0.0, 1.0], "normal_force": W, "tangential_force": T_X1,
                          "preload": "frictionless"})
    pl = cp.plan(sc)
    assert (pl.time_rule, pl.preload) == ("step_start", "frictionless")
    assert pl.describe().endswith("time_rule=step_start, preload=frictionless")


# --------------------------------------------------------------------------- overrides
@pytest.mark.parametrize("kw, tangential, coupling, expected", [
    ({}, "vector", None, ("vector", "none")),
    ({}, "scalar", None, ("scalar", "none")),
    ({}, "auto", None, ("scalar", "none")),
    ({"T": T_X2}, "vector", None, ("vector", "none")),
    ({"halfspace": ALUMINIUM}, "vector", "gauss_seidel", ("vector", "gauss_seidel")),
    ({}, None, "none", ("scalar", "none")),
    ({"T": None}, "none", "none", ("none", "none")),
])
def test_accepted_overrides(kw, tangential, coupling, expected):
    pl = cp.plan(scene(**kw), tangential=tangential, coupling=coupling)
    assert (pl.tangential, pl.coupling) == expected


REFUSALS = [
    ("tangential none under a tangential load", {}, {"tangential": "none"},
     r"^tangential='none': the scene carries shear .*allowed: 'scalar', 'vector', 'auto'$"),
    ("tangential none under Spence's shear", {"halfspace": ALUMINIUM, "T": None},
     {"tangential": "none"}, r"^tangential='none': the scene carries shear"),
    ("scalar with T2", {"T": T_X2}, {"tangential": "scalar"},
     r"^tangential='scalar': load.tangential_force has a component along x2; .*"
     r"Use 'vector' or 'auto'$"),
    ("scalar without shear", {"T": None}, {"tangential": "scalar"},
     r"^tangential='scalar': this scene has no shear to solve \(mu = 0.1, no tangential "
     r"load, no normal-tangential coupling\)$"),
    ("vector when mu = 0", {"halfspace": ALUMINIUM, "T": None, "mu": 0.0},
     {"tangential": "vector"}, r"^tangential='vector': this scene has no shear to solve "
                               r"\(mu = 0.0,"),
    ("bad tangential name", {}, {"tangential": "cattaneo"},
     r"^tangential='cattaneo': allowed 'auto', 'scalar', 'vector', 'none'$"),
    ("coupling none on a coupled pair", {"halfspace": ALUMINIUM}, {"coupling": "none"},
     r"^coupling='none': the pair couples \(Dundurs beta != 0\) .*would drop physics$"),
    ("coupling none on Spence's shear", {"indenter": RIGID, "T": None}, {"coupling": "none"},
     r"^coupling='none': the pair couples"),
    ("gauss_seidel on an identical pair", {}, {"coupling": "gauss_seidel"},
     r"^coupling='gauss_seidel': nothing to couple in this scene \(no shear, or Dundurs "
     r"beta = 0\)$"),
    ("gauss_seidel on rigid on incompressible", {"indenter": RIGID, "halfspace": RUBBER},
     {"coupling": "gauss_seidel"}, r"^coupling='gauss_seidel': nothing to couple"),
    ("gauss_seidel on a coupled pair without friction",
     {"halfspace": ALUMINIUM, "T": None, "mu": 0.0}, {"coupling": "gauss_seidel"},
     r"^coupling='gauss_seidel': nothing to couple"),
    ("gauss_seidel when the tangential form is dropped", {"halfspace": ALUMINIUM, "T": None,
                                                          "mu": 0.0},
     {"tangential": "none", "coupling": "gauss_seidel"},
     r"^coupling='gauss_seidel': nothing to couple"),
    ("bad coupling name", {"halfspace": ALUMINIUM}, {"coupling": "jacobi"},
     r"^coupling='jacobi': allowed \('none', 'gauss_seidel'\)$"),
    ("bad coupling name on an uncoupled pair", {}, {"coupling": "jacobi"},
     r"^coupling='jacobi': allowed \('none', 'gauss_seidel'\)$"),
]


@pytest.mark.parametrize("kw, override, message",
                         [pytest.param(kw, o, m, id=i) for i, kw, o, m in REFUSALS])
def test_refused_overrides(kw, override, message):
    """Each override the scene contradicts is refused with one SceneError line naming the
    option, the value and why (or what is allowed)."""
    with pytest.raises(cp.SceneError, match=message) as err:
        cp.plan(scene(**kw), **override)
    assert "\n" not in str(err.value)


def test_bad_tangential_name_on_a_scene_without_shear():
    """The name is checked before anything else: an unknown one is reported with the
    allowed names even where the scene needs no tangential model."""
    with pytest.raises(cp.SceneError, match=r"^tangential='cattaneo': allowed 'auto', "
                                            r"'scalar', 'vector', 'none'"):
        cp.plan(scene(T=None), tangential="cattaneo")


def test_rules_table_lists_every_slot_and_model():
    assert {slot: models(slot) for slot in RULES} == {
        "normal": ("polonsky_keer",), "tangential": ("none", "scalar", "vector"),
        "coupling": ("none", "gauss_seidel"), "memory": ("none", "recursive", "direct")}
    for slot in RULES:
        assert getattr(cp.plan(scene()), slot) in models(slot)


def test_each_rule_states_when_it_applies_what_it_requires_and_excludes():
    """The table is the inference: every rule is a :class:`Rule` with a predicate; a
    slot's last rule always applies (a plan names every slot); an override is refused by
    the message of the rule's own condition."""
    for slot, rules in RULES.items():
        assert all(isinstance(r, Rule) and callable(r.applies) for r in rules), slot
        for r in rules:
            assert all(callable(c) and callable(m) for c, m in r.requires + r.excludes)
    scalar = next(r for r in RULES["tangential"] if r.model == "scalar")
    assert len(scalar.excludes) == 2                   # a twist, a load along x2
    # steel on steel under T along x1: shear, identical bodies (beta = 0) -> no coupling
    pl = cp.plan(scene())
    assert (pl.tangential, pl.coupling) == ("scalar", "none")
    with pytest.raises(cp.SceneError, match="coupling='gauss_seidel': nothing to couple"):
        cp.plan(scene(), coupling="gauss_seidel")


@pytest.mark.parametrize("value", ["none", "cattaneo"])
def test_scene_solver_tangential_is_validated(value):
    """The scene's own solver.tangential takes 'auto', 'scalar' or 'vector' ('none' is only
    an override of plan/simulate)."""
    with pytest.raises(cp.SceneError, match=rf"^solver.tangential must be one of 'auto', "
                                            rf"'scalar', 'vector', got '{value}'$"):
        scene(solver={"tangential": value})


def test_scene_solver_tangential_is_checked_by_plan():
    """solver.tangential = 'scalar' in the scene is refused like the override when the load
    has an x2 component."""
    with pytest.raises(cp.SceneError, match=r"^tangential='scalar': load.tangential_force "
                                            r"has a component along x2"):
        cp.plan(scene(T=T_X2, solver={"tangential": "scalar"}))


def test_simulate_refuses_like_plan_and_writes_nothing(tmp_path):
    """cp.simulate's overrides go through the same checks, before any file is touched."""
    path = tmp_path / "run.nc"
    with pytest.raises(cp.SceneError, match=r"^coupling='none': the pair couples"):
        cp.simulate(scene(halfspace=ALUMINIUM), path, coupling="none")
    with pytest.raises(cp.SceneError, match=r"^tangential='scalar': load.tangential_force"):
        cp.simulate(scene(T=T_X2), path, tangential="scalar")
    assert list(tmp_path.iterdir()) == []


def test_plan_does_not_depend_on_grid_or_steps():
    """The plan is a property of the physics: grid and step count change nothing (except
    memory with a single instant, tested above)."""
    base = cp.plan(scene(halfspace=ALUMINIUM))
    for over in ({"grid": {"points": [16, 24]}}, {"steps": 7}):
        assert cp.plan(scene(halfspace=ALUMINIUM, **over)) == base


@pytest.mark.parametrize("halfspace, form", [(STEEL, "scalar"), (ALUMINIUM, "scalar"),
                                             (ALUMINIUM, "vector")],
                         ids=["steel-scalar", "aluminium-scalar", "aluminium-vector"])
def test_pair_estimate_is_below_the_pairs_spent(halfspace, form):
    """The planning estimate of a fretting loop (32², 10 steps) stays an order-of-magnitude
    figure below what the run spends, so that ``seconds`` remains a lower bound of the
    wall time: 0.2 <= estimated / spent <= 1."""
    from contactpipe.planning import estimate_resources
    sc = fretting_scene(n=32, steps=10, halfspace=dict(halfspace))
    est = estimate_resources(sc, cp.plan(sc, tangential=form)).fft_pairs
    spent = float(cp.simulate(sc, tangential=form).fft_pairs.sum())
    assert 0.2 <= est / spent <= 1.0, (est, spent)


def test_auto_reads_the_mirror_symmetry_of_maps_and_surfaces(tmp_path):
    """A friction map or a gap surface on the grid: symmetric about x2 = 0, "auto" keeps
    the one-component form (steel pair, T along x1); one that differs from its mirror
    image (mu 0.1 / 0.2 on the two sides of x2 = 0; a sphere's gap tilted along x2)
    needs the vector form, and q2_reasons names the file's key."""
    import numpy as np
    import xarray as xr

    from contactpipe.planning import q2_reasons

    base = scene(grid={"points": [16, 16]})
    x1, x2 = base.resolved_grid().coordinates()
    X1, X2 = np.meshgrid(x1, x2, indexing="ij")

    def mu_map(name, values):
        path = tmp_path / name
        xr.Dataset({"mu": (("x1", "x2"), values)}, coords={"x1": x1, "x2": x2}).to_netcdf(path)
        return str(path)

    even = mu_map("even.nc", 0.1 + 0.1 * (np.abs(X2) > 2 * abs(x2[0])))
    sides = mu_map("sides.nc", np.where(X2 > 0, 0.2, 0.1))
    assert cp.plan(base.replace({"friction.mu": even})).tangential == "scalar"
    odd = base.replace({"friction.mu": sides})
    assert cp.plan(odd).tangential == "vector"
    assert q2_reasons(odd) == ["friction.mu (a map) is not symmetric about x2 = 0"]
    gap = (X1 ** 2 + X2 ** 2) / (2 * 0.018)
    for name, values, form in (("round.npy", gap, "scalar"),
                               ("tilted.npy", gap + 1e-3 * X2, "vector")):
        np.save(tmp_path / name, values)
        sc = base.replace({"geometry": {"shape": "surface", "file": str(tmp_path / name)}})
        assert cp.plan(sc).tangential == form, name
