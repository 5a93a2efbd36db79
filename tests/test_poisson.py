"""A Poisson ratio that varies in time (issue 9, item 5): a shear creep function with an
elastic bulk modulus (``bulk = "elastic"``).

The influence coefficients split into a shear part (1/G) and a Poisson part (nu/G); each
gets its own creep function from the Carson-domain relation
(nu/G)^ = J^/2 - 1/(2K) + (1/(2K))/(1 + 3K J^) (materials.elastic_bulk_parts). Checked:
the kernel factorisation, the creep functions against an independent numerical Laplace
inversion of the Carson transforms (fixed Talbot), the limits (nu = 0.5: no coupling; a
constant nu through the split machinery reproduces the one-part run), and a rigid sphere's
pressure field and contact radius against Lee-Radok with the normal compliance
(1 - nu(t))/G(t), obtained by that Laplace inversion.
"""
import numpy as np
import pytest

import contactpipe as cp
from contactpipe import materials
from contactpipe.materials import (
    Body,
    ExponentialCreep,
    bulk_ratio,
    elastic_bulk_parts,
    kelvin_voigt,
    maxwell,
    prony,
    relaxation_from_creep,
    zener,
)
from contactpipe.planning import plan
from contactpipe.solver.influence import body_kernel_parts, body_kernels
from contactpipe.solver.memory import BodyMemory, RecursiveMemory
from contactpipe.testing import lee_radok_measures

R, W, E, NU = 0.018, 1000.0, 105e9, 0.3
PRONY3 = [[0.5, 0.1], [1.0, 1.0], [2.0, 5.0]]
CREEPS = {"maxwell": maxwell(1.0), "zener100": zener(100.0, 1.0, 1.0),
          "zener2": zener(2.0, 1.0, 1.0), "kelvin_voigt": kelvin_voigt(1.0),
          "prony3": prony(PRONY3, 10.0)}
KEYS = {"maxwell": {"creep": "maxwell", "relaxation_time": 1.0},
        "prony3": {"creep": "prony", "terms": PRONY3, "relaxation_time": 10.0}}


def talbot(F, t, M=32):
    """Fixed-Talbot inversion (Abate & Valko 2004) of the Laplace transform F(s) at t > 0;
    about 1e-11 relative here (checked on 1/(s + 1))."""
    r = 2.0 * M / (5.0 * t)
    th = np.arange(1, M) * np.pi / M
    cot = 1.0 / np.tan(th)
    s = r * th * (cot + 1j)
    sigma = th + (th * cot - 1.0) * cot
    val = 0.5 * np.exp(r * t) * F(np.array([r + 0j]))[0].real
    val += np.sum((np.exp(t * s) * F(s) * (1 + 1j * sigma)).real)
    return r / M * val


def carson_compliances(creep, nu):
    """The Carson transforms of the normalised normal and coupling compliances
    (1 - nu)/G and (1 - 2 nu)/G of a shear creep phi with an elastic bulk (kappa = G/K),
    written from nu^ = (3K - 2G^)/(2(3K + G^)) directly."""
    kappa = bulk_ratio(nu)

    def normal(s):
        j = creep.stieltjes(s)                       # G J^ = phi^
        g = 1.0 / j                                  # G^/G
        nu_s = (3.0 / kappa - 2.0 * g) / (2.0 * (3.0 / kappa + g))
        return (1.0 - nu_s) * j / (1.0 - nu)

    def coupling(s):
        j = creep.stieltjes(s)
        g = 1.0 / j
        nu_s = (3.0 / kappa - 2.0 * g) / (2.0 * (3.0 / kappa + g))
        return (1.0 - 2.0 * nu_s) * j / (1.0 - 2.0 * nu)

    return normal, coupling


def inverted(carson, phi0):
    """The function of a Carson transform by Laplace inversion (phi0 at t <= 0)."""
    def f(t):
        t = np.asarray(t, float)
        out = np.array([phi0 if ti <= 0 else talbot(lambda s: carson(s) / s, ti)
                        for ti in t.ravel()])
        return out.reshape(t.shape) if t.ndim else float(out[0])
    return f


def test_talbot_is_accurate():
    assert talbot(lambda s: 1.0 / (s + 1.0), 1.0) == pytest.approx(np.exp(-1.0), rel=1e-10)
    assert talbot(lambda s: 1.0 / s ** 2, 2.5) == pytest.approx(2.5, rel=1e-10)


# --------------------------------------------------------------------------- kernels
@pytest.mark.parametrize("nu", [0.0, 0.2, 0.3, 0.45, 0.5])
def test_kernel_parts_factor(nu):
    """K(G, nu) = K_shear + nu K_poisson at a fixed shear modulus, every kernel, 24 x 16 cells
    of 10 x 20 um: to 1e-14 of each kernel's largest value (measured 4e-16)."""
    g = 1e9
    full = body_kernels(24, 16, 1e-5, 2e-5, 2 * g * (1 + nu), nu)
    shear, part = body_kernel_parts(24, 16, 1e-5, 2e-5, g)
    for key, k in full.items():
        scale = max(np.abs(shear[key]).max(), np.abs(part[key]).max())
        assert np.abs(k - (shear[key] + nu * part[key])).max() <= 1e-14 * scale, key
    assert np.all(shear["12"] == 0)
    np.testing.assert_allclose(shear["13"] + 0.5 * part["13"], 0.0, atol=1e-14 * scale)


# --------------------------------------------------------------------------- creep functions
@pytest.mark.parametrize("name", list(CREEPS))
@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45])
def test_compliances_against_laplace_inversion(name, nu):
    """The normal and coupling compliances of Body.normal_creep / coupling_creep (exact
    pole-residue interconversion) against the Talbot inversion of their Carson transforms,
    at t = 0.05, 0.5, 2 tau: within 1e-9 (measured 4e-12 to 1.4e-10); both start at 1 (0
    for Kelvin-Voigt, exactly), have non-negative terms (they are creep functions) and the
    Poisson part starts at nu."""
    creep = CREEPS[name]
    body = Body("viscoelastic", 1e9, nu, creep, "elastic")
    assert body.split
    normal, coupling = carson_compliances(creep, nu)
    for t in (0.05, 0.5, 2.0):
        assert float(body.normal_creep(t)) == pytest.approx(
            talbot(lambda s: normal(s) / s, t), abs=1e-9)
        assert float(body.coupling_creep(t)) == pytest.approx(
            talbot(lambda s: coupling(s) / s, t), abs=1e-9)
    phi0 = creep.phi0
    assert body.normal_creep.phi0 == pytest.approx(phi0, abs=1e-14)
    assert body.coupling_creep.phi0 == pytest.approx(phi0, abs=1e-12)   # 1/(1 - 2 nu)
    if phi0 == 0:
        assert body.normal_creep.phi0 == 0.0 and body.part_creeps[1].phi0 == 0.0
    else:
        assert body.part_creeps[1].phi0 == pytest.approx(nu * phi0, abs=1e-14)
    for c in (body.normal_creep, body.coupling_creep):
        assert c.b >= 0 and all(d <= 0 for d in c.d)


def test_relaxation_from_creep_closed_forms():
    """Zener: the relaxation function of phi = r - (r - 1) exp(-t/tau) is
    1/r + (1 - 1/r) exp(-t r/tau) (r = E0/Einf); Maxwell exp(-t/t'); Kelvin-Voigt has only
    the Dirac part and a constant regular part 1; r(0) = 1/(phi0 + extra)."""
    z = relaxation_from_creep(zener(4.0, 1.0, 2.0))
    t = np.linspace(0, 5, 11)
    np.testing.assert_allclose(z(t), 0.25 + 0.75 * np.exp(-t * 4 / 2.0), rtol=1e-12)
    np.testing.assert_allclose(relaxation_from_creep(maxwell(0.7))(t), np.exp(-t / 0.7),
                               rtol=1e-12)
    kv = relaxation_from_creep(kelvin_voigt(1.0))
    assert kv.d == () and kv.a == pytest.approx(1.0)
    p = relaxation_from_creep(prony(PRONY3, 10.0), 0.2)
    assert float(p(0.0)) == pytest.approx(1.0 / 1.2, rel=1e-12)


def test_coupling_fades_as_nu_grows():
    """Maxwell shear with an elastic bulk: nu(t) = part/shear grows from nu0 towards 1/2, and
    the coupling compliance stays bounded (kappa) while the normal one grows without bound:
    their ratio falls (nu0 = 0.3: nu = 0.479 and the ratio 0.14 at 10 t', 0.49998 and
    1.6e-4 at 1e4 t')."""
    body = Body("viscoelastic", 1e9, 0.3, maxwell(1.0), "elastic")
    shear, part = body.part_creeps
    t = np.array([0.0, 0.5, 2.0, 10.0, 100.0, 1e4])
    nu_t = part(t) / shear(t)
    assert nu_t[0] == pytest.approx(0.3) and np.all(np.diff(nu_t) > 0) and nu_t[-1] < 0.5
    assert nu_t[-1] > 0.4999
    ratio = body.coupling_creep(t) / body.normal_creep(t)
    assert ratio[0] == pytest.approx(1.0) and np.all(np.diff(ratio) < 0) and ratio[-1] < 2e-4
    assert float(body.coupling_creep(1e6)) <= bulk_ratio(0.3) / (1 - 2 * 0.3) + 1e-12


# --------------------------------------------------------------------------- the limits
def scene(bulk=None, nu=NU, mu=0.0, tangential=False, n=32, steps=10, law="maxwell",
          size="auto"):
    hs = {"material": "viscoelastic", "young": E, "poisson": nu, **KEYS[law]}
    if bulk:
        hs["bulk"] = bulk
    load = {"time": [0.0, 2.0], "normal_force": W}
    if tangential:
        load["tangential_force"] = [0.0, 0.5 * mu * W]
    return cp.Scene(name="nu-t", geometry={"shape": "sphere", "radius": R},
                    indenter={"material": "rigid"}, halfspace=hs, friction={"mu": mu},
                    load=load, grid={"points": [n, n], "size": size}, time={"steps": steps},
                    solver={"tolerance": 1e-10})


def test_incompressible_limit_has_no_coupling():
    """nu = 0.5 with an elastic bulk (K infinite): nu stays 0.5, one kernel part, the plan's
    coupling slot is "none" for the rigid indenter, and under a normal load with friction
    the shear is zero at every instant."""
    sc = scene("elastic", nu=0.5, mu=0.3)
    body = sc.halfspace.body()
    assert not body.split and len(body.part_creeps) == 1
    assert plan(sc).coupling == "none" and plan(sc).tangential == "none"
    sc = scene("elastic", nu=0.5, mu=0.3, tangential=True)
    assert plan(sc).coupling == "none"
    ds = cp.simulate(scene("elastic", nu=0.5, mu=0.3, tangential=True))
    assert np.all(ds.q1.values[0] == 0)
    assert plan(scene("elastic", nu=0.3, mu=0.3, tangential=True)).coupling == "gauss_seidel"


def test_constant_nu_through_the_split_machinery(monkeypatch):
    """The two-part machinery (shear and Poisson kernel parts, two recursions, weighted
    operators) fed the parts (phi, nu phi) of a constant Poisson ratio reproduces the
    one-part run: a coupled fretting case (rigid ball on Maxwell, nu = 0.3, mu = 0.3,
    T 0 -> 0.15 W, frictional preload, 24^2, 8 steps): p, q and u within 1e-8 of their
    largest values (measured 1e-12 to 1.3e-10: the round-off of the weighted sum moves
    the iterations of a 1e-10 tolerance by one or two)."""
    base = cp.simulate(scene(mu=0.3, tangential=True, n=24, steps=8))

    def constant_parts(creep, poisson):
        return creep, materials.combine([(poisson, creep)], "poisson_part")

    monkeypatch.setattr(materials, "elastic_bulk_parts", constant_parts)
    split = cp.simulate(scene("elastic", mu=0.3, tangential=True, n=24, steps=8))
    assert split.attrs.get("halfspace_poisson_model") and not base.attrs.get(
        "halfspace_poisson_model")
    for v in ("p", "q1", "u1", "u3", "omega3"):
        a, b = base[v].values, split[v].values
        assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max(), v
    assert split.attrs["time_rule_resolved"] == base.attrs["time_rule_resolved"]


def test_body_memory_state_round_trip():
    """The parts' recursions checkpoint and restore as one memory."""
    body = Body("viscoelastic", 1e9, 0.3, prony(PRONY3, 10.0), "elastic")
    rng = np.random.default_rng(0)
    a = BodyMemory([RecursiveMemory(c, 0.1, "bdf2", (3, 4)) for c in body.part_creeps])
    for _ in range(5):
        a.commit(rng.normal(size=(3, 4)))
    b = BodyMemory([RecursiveMemory(c, 0.1, "bdf2", (3, 4)) for c in body.part_creeps])
    b.load_state({k: np.array(v) for k, v in a.state().items()})
    for _ in range(3):
        assert b.instant_weight == a.instant_weight
        for x, y in zip(a.known(), b.known(), strict=True):
            np.testing.assert_array_equal(x, y)
        s = rng.normal(size=(3, 4))
        a.commit(s)
        b.commit(s)


def test_split_recursion_is_linear_in_the_parts():
    """The history of the normal compliance equals the difference of the parts' histories
    (one rule per body, coefficients shared per time constant): 200 random steps, "bdf2"
    and "linear", to 1e-12 of the largest history."""
    body = Body("viscoelastic", 1e9, 0.3, zener(100.0, 1.0, 1.0), "elastic")
    shear, part = body.part_creeps
    rng = np.random.default_rng(1)
    for rule in ("bdf2", "linear"):
        parts = BodyMemory([RecursiveMemory(c, 0.05, rule, (5,)) for c in (shear, part)])
        normal = RecursiveMemory(body.normal_creep, 0.05, rule, (5,))
        worst = scale = 0.0
        for _ in range(200):
            ks, kp = parts.known()
            kn = normal.known() * (1 - 0.3)
            worst = max(worst, float(np.abs(ks - kp - kn).max()))
            scale = max(scale, float(np.abs(kn).max()))
            ws, wp = parts.instant_weight
            assert ws - wp == pytest.approx((1 - 0.3) * normal.instant_weight, abs=1e-12)
            s = rng.normal(size=5)
            parts.commit(s)
            normal.commit(s)
        assert worst <= 1e-12 * scale


# --------------------------------------------------------------------------- Lee-Radok
@pytest.mark.parametrize("law,bound", [("maxwell", 0.006), ("prony3", 0.008)])
def test_lee_radok_with_varying_poisson_ratio(law, bound):
    """Rigid sphere, W = 1 kN stepped at t0, shear creep (Maxwell t' = 1 s; the 3-term Prony
    series with a dashpot) with an elastic bulk, nu0 = 0.3, 48^2 auto-sized, 20 steps over
    2 s ("auto": "linear"). The normal problem depends on (1 - nu(t))/G(t) alone: Lee-Radok
    with that compliance, computed independently by Talbot inversion of its Carson
    transform. Radius from the area within 1 cell for t >= 0.25 s (measured 0.21, 0.17), no
    hole, no zigzag of the centre pressure, a^3 from the approach within 0.2 % (measured
    0.056 %, 0.053 %), the field inside 0.8 a within the stated fraction of the centre
    pressure for t >= 0.25 s (measured 0.27 %, 0.41 %). The varying nu matters: a(2 s) is
    6 % below the constant-nu contact radius (a^3 ratio n(2)/phi(2) = 0.82 for Maxwell)."""
    sc = scene("elastic", n=48, steps=20, law=law)
    ds = cp.simulate(sc)
    assert ds.attrs["time_rule_resolved"] == "halfspace: linear"
    normal, _ = carson_compliances(sc.halfspace.body().creep, NU)
    n_t = inverted(normal, 1.0)
    m = lee_radok_measures(ds, n_t, E, NU, R, W, t_min=0.25, t_field=0.25, field_every=3,
                           n_steps=400)
    assert m["radius_cells"] < 1.0
    a_om = np.sqrt(R * ds.omega3.values)
    assert np.abs(a_om[1:] ** 3 / m["a_exact"][1:] ** 3 - 1).max() < 2e-3
    assert m["holes"] == 0
    assert m["zigzag"] < 1e-3
    assert m["field"] < bound
    if law == "maxwell":
        body = sc.halfspace.body()
        ratio = float(body.normal_creep(2.0)) / float(body.creep(2.0))
        assert ratio == pytest.approx(0.8216, abs=1e-3)


def test_scene_keys():
    """bulk is a viscoelastic key; "creep" is the default and is stored as absent (same
    digest); a table cannot take an elastic bulk."""
    a, b = scene(), scene("creep")
    assert a == b and a.digest() == b.digest() and "bulk" not in b.to_dict()["halfspace"]
    c = scene("elastic")
    assert c.to_dict()["halfspace"]["bulk"] == "elastic" and c.digest() != a.digest()
    assert cp.Scene.from_toml_text(c.to_toml()) == c
    with pytest.raises(cp.SceneError, match=r"halfspace\.bulk = 'elastic' is not used by an "
                                            r"elastic body"):
        cp.Scene(**{**a.to_dict(), "halfspace": {"material": "elastic", "young": E,
                                                 "poisson": NU, "bulk": "elastic"}})
    with pytest.raises(cp.SceneError, match=r"halfspace\.bulk = 'elastic' needs a creep law "
                                            r"of exponentials"):
        cp.Scene(**{**a.to_dict(), "halfspace": {
            "material": "viscoelastic", "young": E, "poisson": NU, "creep": "tabulated",
            "table": [[0.0, 1.0], [3.0, 2.0]], "bulk": "elastic"}})
    with pytest.raises(cp.SceneError, match=r"halfspace\.bulk must be one of 'creep', "
                                            r"'elastic', got 'rigid'"):
        scene("rigid")


def test_step_start_bound_counts_the_normal_compliance():
    """With a varying nu the step-start rule's bound is the smaller of phi's and the normal
    compliance's (Maxwell t' = 1 s, nu0 = 0.3: 2 t' for phi, larger for (1 - nu)/G, whose
    rate at t0 is smaller): a step of 1.9 s is accepted, 2.1 s refused."""
    body = Body("viscoelastic", E, NU, maxwell(1.0), "elastic")
    bounds = [materials.step_start_stable_step(c) for c in body.rule_creeps]
    assert bounds[0] == pytest.approx(2.0) and bounds[1] > bounds[0]
    ok = scene("elastic", steps=2).replace({"solver.time_rule": "step_start",
                                            "time.steps": 2})
    assert ok.time.steps == 2
    with pytest.raises(cp.SceneError, match="not below its stability bound 2 s"):
        ok.replace({"load.time": [0.0, 4.2]})


def test_exponential_creep_is_what_the_parts_are():
    """The parts are plain ExponentialCreep objects (the O(N) recursion applies)."""
    for c in elastic_bulk_parts(prony(PRONY3, 10.0), 0.3):
        assert isinstance(c, ExponentialCreep)
