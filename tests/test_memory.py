"""Viscoelastic memory: recursion = direct Boltzmann sum; Lee-Radok creep of a rigid sphere.

Lee & Radok (1960): under a constant load W stepped at t = 0 the contact radius of a rigid
sphere on a viscoelastic half-space (constant ν) follows a(t)³ = 3 W R (1 − ν²) φ(t) / (4E).
The radius is measured through the approach, a = √(R ω3) (the paraboloid's geometric
relation, exact in Lee-Radok's solution); the radius from the contact area is reported too.
"""
import numpy as np
import pytest

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.materials import TabulatedCreep, kelvin_voigt, maxwell, prony, zener
from contactpipe.solver.memory import DirectMemory, RecursiveMemory, make_memory

R, W, E, NU = 0.018, 1000.0, 105e9, 0.3


@pytest.mark.parametrize("creep", [maxwell(1.0), kelvin_voigt(0.7), zener(3.0, 1.0, 0.4),
                                   prony([[0.5, 0.3], [1.0, 2.0]], 1.5)],
                         ids=["maxwell", "kelvin_voigt", "zener", "prony"])
@pytest.mark.parametrize("rule", ["linear", "step_start"])
def test_recursion_equals_direct_sum(creep, rule):
    """The O(N) recursion reproduces the O(kN) Boltzmann sum to rounding (40 random steps)."""
    rng = np.random.default_rng(0)
    a, b = RecursiveMemory(creep, 0.1, rule, (3, 4)), DirectMemory(creep, 0.1, rule, (3, 4))
    for _ in range(40):
        assert a.instant_weight == pytest.approx(b.instant_weight, rel=1e-12)
        np.testing.assert_allclose(a.known(), b.known(), rtol=1e-11, atol=1e-11)
        s = rng.normal(size=(3, 4))
        a.commit(s)
        b.commit(s)



@pytest.mark.parametrize("rule", ["bdf2", "linear", "step_start"])
def test_known_part_formed_once_leaves_the_state_unchanged(rule):
    """known() keeps the past's share of an instant for commit(): a memory asked for it
    once, twice or never per instant holds bit for bit the same state after 30 random
    steps, a reloaded one as well; and under a constant traction after the jump the
    Maxwell history is the closed form H(t_k) = sigma (1 + t_k / t') to 1e-12."""
    rng = np.random.default_rng(1)
    creep = prony([[0.5, 0.3], [1.0, 2.0]], 1.5)
    asked = [RecursiveMemory(creep, 0.1, rule, (3, 4)) for _ in range(4)]
    for k in range(30):
        s = rng.normal(size=(3, 4))
        for times, m in zip((0, 1, 2), asked[:3], strict=True):
            for _ in range(times):
                m.known()
        if k == 15:          # a checkpoint restored between known() and commit()
            asked[3].known()
            state = {key: np.copy(v) for key, v in asked[3].state().items()}
            asked[3] = RecursiveMemory(creep, 0.1, rule, (3, 4))
            asked[3].load_state(state)
        for m in asked:
            m.commit(s)
    for m in asked[1:]:
        for key, v in asked[0].state().items():
            np.testing.assert_array_equal(np.asarray(m.state()[key]), np.asarray(v))
    m, sigma, dt = RecursiveMemory(maxwell(1.0), 0.05, "linear", (2,)), np.array([2.0, 3.0]), 0.05
    m.commit(sigma)
    for k in range(1, 40):
        h = m.known() + m.instant_weight * sigma
        np.testing.assert_allclose(h, sigma * (1.0 + k * dt), rtol=1e-12)
        m.commit(sigma)

def test_tabulated_creep_uses_direct_sum():
    tab = TabulatedCreep(t=(0.0, 1.0, 2.0), phi=(1.0, 2.0, 3.0))
    assert isinstance(make_memory(tab, 0.1, "linear", (2,)), DirectMemory)
    assert isinstance(make_memory(maxwell(1.0), 0.1, "linear", (2,)), RecursiveMemory)


@pytest.mark.parametrize("rule", ["bdf2", "linear", "step_start"])
def test_recursion_state_does_not_grow(rule):
    """Memory per step is flat: the recursion holds the same arrays after 10 and 1000 steps."""
    m = RecursiveMemory(prony([[0.5, 0.3]], 1.5), 0.01, rule, (8, 8))
    sizes = []
    for k in range(1000):
        m.commit(np.full((8, 8), float(k)))
        if k in (9, 999):
            sizes.append(sum(np.asarray(v).nbytes for v in m.state().values()))
    assert sizes[0] == sizes[1]


def creep_scene(creep_keys, rule, steps, n=96, load=None):
    return cp.Scene(name="lee-radok", geometry={"shape": "sphere", "radius": R},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU, **creep_keys},
                    load=load or {"time": [0.0, 2.0], "normal_force": W},
                    grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                    solver={"time_rule": rule, "tolerance": 1e-10})


def lee_radok_error(ds, creep, t_min=0.0):
    t = ds.time.values
    a_num = np.sqrt(R * np.clip(ds.omega3.values, 0, None))
    a_ex = an.lee_radok_sphere(t, W, R, E, NU, creep).contact_radius
    m = t >= t_min
    return np.abs(a_num[m] ** 3 / a_ex[m] ** 3 - 1).max()


CASES = {
    "maxwell": ({"creep": "maxwell", "relaxation_time": 1.0}, maxwell(1.0)),
    "zener": ({"creep": "zener", "relaxed_young": E / 3, "retardation_time": 0.5},
              zener(E, E / 3, 0.5)),
}


@pytest.mark.parametrize("name", list(CASES))
def test_lee_radok_step_load(name):
    """Maxwell (t' = 1 s) and Zener (E∞ = E0/3, τ = 0.5 s), W stepped at 0, window 2 s,
    96 x 96 auto-sized grid, 20 steps: a(t)³ within 1 % of Lee-Radok with the second-order
    rule (measured < 1e-4); the step-start rule is reported beside it (for a step load
    both rules agree: the increments after the step are small redistributions)."""
    keys, creep = CASES[name]
    err_lin = lee_radok_error(cp.simulate(creep_scene(keys, "linear", 20)), creep)
    err_ss = lee_radok_error(cp.simulate(creep_scene(keys, "step_start", 20)), creep)
    assert err_lin < 0.01, f"Lee-Radok ({name}, linear rule): {err_lin:.2e}"
    assert err_ss < 0.01, f"Lee-Radok ({name}, step-start rule): {err_ss:.2e}"


def test_lee_radok_kelvin_voigt():
    """Kelvin-Voigt (no instantaneous elasticity), τ = 0.5 s, 128 x 128 auto-sized, 80 steps,
    second-order rule: a(t)³ within 1 % of Lee-Radok for t ≥ 0.2τ (measured 0.5 %; 1.9 % with
    20 steps: first order, from the concentrated load at the instant of the step)."""
    creep = kelvin_voigt(0.5)
    ds = cp.simulate(creep_scene({"creep": "kelvin_voigt", "retardation_time": 0.5}, "linear",
                                 80, n=128))
    err = lee_radok_error(ds, creep, t_min=0.1)
    assert err < 0.01, f"Lee-Radok (Kelvin-Voigt): {err:.2e}"
    # at the instant of the step the rigid response puts W on the cells of least gap
    assert float(ds.W[0]) == pytest.approx(W, rel=1e-12)


def test_kelvin_voigt_refuses_step_start_rule():
    with pytest.raises(cp.SceneError, match="time_rule"):
        creep_scene({"creep": "kelvin_voigt", "retardation_time": 0.5}, "step_start", 10)


@pytest.mark.parametrize("rule,steps,bound", [("linear", 10, 0.002), ("step_start", 10, 0.10),
                                              ("step_start", 40, 0.03)])
def test_ramp_load_time_rules(rule, steps, bound):
    """W ramped 0 -> 1 kN over t' then held (Maxwell, 64² auto-sized): Lee-Radok's hereditary
    integral for t ≥ 0.25 s. The linear rule is exact in time for φ linear (measured 4e-4,
    spatial); the step-start rule is first order (measured 8.4 % at 10 steps, 2.3 % at 40)."""
    load = {"time": [0.0, 1.0, 2.0], "normal_force": [0.0, W, W]}
    ds = cp.simulate(creep_scene({"creep": "maxwell", "relaxation_time": 1.0}, rule, steps,
                                 n=64, load=load))
    t = ds.time.values
    a_ex = an.lee_radok_radius(t, [0.0, 1.0, 2.0], [0.0, W, W], R, E, NU, maxwell(1.0))
    a_num = np.sqrt(R * np.clip(ds.omega3.values, 0, None))
    m = t >= 0.25
    err = np.abs(a_num[m] ** 3 / a_ex[m] ** 3 - 1).max()
    assert err < bound


def test_elastic_scene_has_no_memory():
    sc = cp.Scene(name="el", geometry={"shape": "sphere", "radius": R},
                  indenter={"material": "rigid"},
                  halfspace={"material": "elastic", "young": E, "poisson": NU},
                  load={"time": [0.0, 1.0], "normal_force": [0.0, W]},
                  grid={"points": [32, 32], "size": "auto"}, time={"steps": 4})
    assert cp.plan(sc).memory == "none"
    assert "memory=none" in cp.simulate(sc).attrs["models"]


def test_two_viscoelastic_bodies_each_with_its_own_memory():
    """A Maxwell sphere (t' = 0.5 s, E = 70 GPa) on a Zener half-space (E0 = 105 GPa, E∞ = E0/3,
    τ = 1 s), ν = 0.5 on both (no coupling), W stepped at 0, 96² auto-sized, 20 steps over
    2 s: the normal problem depends on the sum of the compliances, so Lee-Radok holds with
    a(t)³ = 3WR/4 · Σ (1 − ν²)/E φ(t). Each body keeps its own history; measured 2.1e-4."""
    sc = cp.Scene(name="two-bodies", geometry={"shape": "sphere", "radius": R},
                  indenter={"material": "viscoelastic", "young": 70e9, "poisson": 0.5,
                            "creep": "maxwell", "relaxation_time": 0.5},
                  halfspace={"material": "viscoelastic", "young": E, "poisson": 0.5,
                             "creep": "zener", "relaxed_young": E / 3, "retardation_time": 1.0},
                  load={"time": [0.0, 2.0], "normal_force": W},
                  grid={"points": [96, 96], "size": "auto"}, time={"steps": 20},
                  solver={"tolerance": 1e-10})
    ds = cp.simulate(sc)
    assert "memory=recursive" in ds.attrs["models"] and "coupling=none" in ds.attrs["models"]
    t = ds.time.values
    compliance = (0.75 / 70e9) * maxwell(0.5)(t) + (0.75 / E) * zener(E, E / 3, 1.0)(t)
    a3_exact = 3 * W * R / 4 * compliance
    a3 = (R * ds.omega3.values) ** 1.5
    err = np.abs(a3 / a3_exact - 1).max()
    assert err < 1e-3, f"Lee-Radok with two viscoelastic bodies: {err:.2e}"
