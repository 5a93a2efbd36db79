"""Frictional contact with stick and slip: Mindlin-Deresiewicz, coupling, limits, both forms.

Every archive made here also passes :func:`contactpipe.testing.assert_contact_laws`
(equilibrium, complementarity, Coulomb |q| ≤ μp(1 + 1e-9), dissipation sign, stick).
"""
import numpy as np
import pytest
from helpers import A_HERTZ, E_STAR_STEEL, MU, R, W, fretting_scene, make_scene

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.pipeline.compare import compare
from contactpipe.testing import assert_contact_laws

ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}
COMPLIANCE = an.tangential_compliance_sum(210e9, 0.3, 210e9, 0.3)


@pytest.fixture(scope="module")
def paper_loop():
    """The paper's figure 2 loop: 128 x 128 over 3a, 40 steps (T: 0 -> .9μW -> -.9μW -> .9μW)."""
    ds = cp.simulate(fretting_scene(n=128, steps=40))
    assert_contact_laws(ds)
    return ds


def test_shear_traction_against_mindlin_deresiewicz(paper_loop):
    """q1 against the closed form averaged over each cell, measured as ``contactpipe
    compare`` measures it (the README quotes these figures): max |q1 - q_MD| / (μp0) over
    every cell and instant (measured 6.8 %: the cells a stick/slip circle cuts, where the
    closed form has a square-root kink), the same away from those circles and the contact
    edge (1.4 %), and the RMS over the contact (0.77 %)."""
    table = compare(paper_loop)
    worst = {k: float(table[k].max()) for k in ("err_q1_max", "err_q1_max_interior",
                                                "err_q1_rms")}
    assert worst["err_q1_max"] < 0.10, worst
    assert worst["err_q1_max_interior"] < 0.02, worst
    assert worst["err_q1_rms"] < 0.01, worst


def test_stick_radius(paper_loop):
    """Stick radius from the stick area within two cells of Mindlin-Deresiewicz (measured 0.2)."""
    ds = paper_loop
    d = float(ds.x1[1] - ds.x1[0])
    T = ds.T1.values
    a = an.hertz_sphere(W, R, E_STAR_STEEL).contact_radius
    c_ex = np.array([an.stick_radius(T[:k + 1], MU, W, a) for k in range(len(T))])
    c_num = np.sqrt(ds.stick_area.values / np.pi)
    assert np.abs(c_num - c_ex)[1:].max() / d < 2.0


def test_hysteresis_loop_and_energy(paper_loop):
    """T-ω1 loop within 2 % of its amplitude (measured 2e-5) and the energy of one cycle
    within 2 % (measured 2e-5) of Mindlin-Deresiewicz."""
    ds = paper_loop
    T = ds.T1.values
    a = an.hertz_sphere(W, R, E_STAR_STEEL).contact_radius
    om_ex = an.tangential_displacement(T, MU, W, a, COMPLIANCE, all_instants=True)
    om = ds.omega1.values
    assert np.abs(om - om_ex).max() / np.abs(om_ex).max() < 0.02, "MD compliance loop"
    k1 = int(np.argmin(np.abs(ds.time.values - 0.2)))            # at +T*
    e_num = float(ds.dissipation[-1] - ds.dissipation[k1])        # +T* -> -T* -> +T*
    e_ex = an.energy_per_cycle(0.9 * MU * W, MU, W, a, COMPLIANCE)
    assert e_num == pytest.approx(e_ex, rel=0.02), "MD energy per cycle"
    assert np.all(np.diff(ds.dissipation.values) >= 0)


def test_identical_or_incompressible_pairs_skip_coupling():
    """β = 0: one normal and one tangential solve per step; coupling recorded as none."""
    for pair in ({}, {"indenter": {"material": "elastic", "young": 210e9, "poisson": 0.5},
                      "halfspace": {"material": "elastic", "young": 70e9, "poisson": 0.5}}):
        ds = cp.simulate(fretting_scene(n=32, steps=10, **pair))
        assert "coupling=none" in ds.attrs["models"]
        assert np.all(ds.coupling_passes.values == 1)
        assert_contact_laws(ds)


def test_coupling_shifts_pressure_to_trailing_side():
    """Steel sphere on aluminium (β ≠ 0, the half-space dominates the coupling), T: 0 -> 0.8μW,
    64 x 64 over 4a: the tangential traction on the half-space depresses its surface ahead
    of the force ((1−2ν) Cerruti term, reciprocal of the inward Boussinesq displacement), so
    the pressure centroid moves against T, monotonically (measured −0.09 cell at 0.8μW)."""
    for preload in ("frictionless", "frictional"):
        sc = make_scene(halfspace=ALUMINIUM, friction={"mu": MU},
                        load={"time": [0.0, 1.0], "normal_force": W,
                              "tangential_force": [0.0, 0.8 * MU * W], "preload": preload},
                        grid={"points": [64, 64], "size": [4 * A_HERTZ] * 2}, time={"steps": 8})
        ds = cp.simulate(sc)
        assert "coupling=gauss_seidel" in ds.attrs["models"]
        assert f"preload={preload}" in ds.attrs["models"]
        assert np.all(ds.coupling_passes.values[1:] > 1)
        p, x1 = ds.p.values, ds.x1.values
        xc = (p * x1[None, :, None]).sum(axis=(1, 2)) / p.sum(axis=(1, 2))
        assert np.all(np.diff(xc) < 0), f"centroid {xc}"
        assert_contact_laws(ds)


def test_spence_shear_during_frictional_preload():
    """β ≠ 0 and friction during indentation (the default preload): shear appears with no
    tangential load (Spence), antisymmetric in x1, with zero resultant; with the paper's
    frictionless preload the first instant has no shear."""
    base = dict(halfspace=ALUMINIUM, friction={"mu": MU},
                grid={"points": [48, 48], "size": [3 * A_HERTZ] * 2}, time={"steps": 2})
    fr = cp.simulate(make_scene(load={"time": [0.0, 1.0], "normal_force": W,
                                      "tangential_force": [0.0, 0.5 * MU * W]}, **base))
    q0 = fr.q1.isel(time=0).values
    assert np.abs(q0).max() > 0.01 * MU * float(fr.p.isel(time=0).max())
    np.testing.assert_allclose(q0, -q0[::-1, :], atol=1e-6 * np.abs(q0).max())
    assert abs(float(fr.T1[0])) < 1e-9 * W
    nf = cp.simulate(make_scene(load={"time": [0.0, 1.0], "normal_force": W,
                                      "preload": "frictionless",
                                      "tangential_force": [0.0, 0.5 * MU * W]}, **base))
    assert np.all(nf.q1.isel(time=0).values == 0)


def test_mu_to_zero_gives_frictionless_pressure():
    """μ = 1e-6 on a coupled pair: the pressure equals the frictionless one (measured 3e-7 p0)."""
    grid = {"points": [64, 64], "size": [3 * A_HERTZ] * 2}
    fr = cp.simulate(make_scene(halfspace=ALUMINIUM, friction={"mu": 1e-6}, grid=grid,
                                time={"steps": 4},
                                load={"time": [0.0, 1.0], "normal_force": W,
                                      "tangential_force": [0.0, 0.5e-6 * W]}))
    fl = cp.simulate(make_scene(halfspace=ALUMINIUM, grid=grid, time={"steps": 4},
                                load={"time": [0.0, 1.0], "normal_force": W}))
    p_fl = fl.p.values[-1]
    assert np.abs(fr.p.values[-1] - p_fl).max() / p_fl.max() < 1e-5
    assert_contact_laws(fr)


def test_near_gross_sliding_converges():
    """T = 0.999μW (64 x 64 over 3a, 10 steps): converges, the stick zone nearly vanishes
    (measured 1.1 % of the contact area; Cattaneo: (c/a)² = 0.001^(2/3) = 1 %)."""
    sc = make_scene(friction={"mu": MU}, grid={"points": [64, 64], "size": [3 * A_HERTZ] * 2},
                    load={"time": [0.0, 1.0], "normal_force": W,
                          "tangential_force": [0.0, 0.999 * MU * W]}, time={"steps": 10})
    ds = cp.simulate(sc)
    frac = float(ds.stick_area[-1] / ds.contact_area[-1])
    assert 0 < frac < 0.05
    assert_contact_laws(ds)


def test_gross_sliding_refused():
    with pytest.raises(cp.SceneError, match="gross sliding"):
        make_scene(friction={"mu": MU}, load={"time": [0.0, 1.0], "normal_force": W,
                                              "tangential_force": [0.0, 1.01 * MU * W]})


def loading(n=64, steps=10, direction=(1.0, 0.0), tangential=None):
    Ts = 0.9 * MU * W
    T = [[0.0, 0.0], [Ts * direction[0], Ts * direction[1]]]
    sc = make_scene(friction={"mu": MU}, grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                    load={"time": [0.0, 1.0], "normal_force": W, "tangential_force": T},
                    time={"steps": steps})
    return cp.simulate(sc, tangential=tangential)


def test_vector_form_agrees_with_scalar_along_x1():
    """Load along x1 (64 x 64 over 3a, 10 steps to 0.9μW): the vector solution's q1 differs
    from the one-component form's by no more than the q2 it carries."""
    sca = loading(tangential="scalar")
    vec = loading(tangential="vector")
    assert "tangential=vector" in vec.attrs["models"]
    dq = np.abs(vec.q1.values - sca.q1.values).max()
    q2 = np.abs(vec.q2.values).max()
    assert dq <= 1.5 * q2 and q2 < 0.1 * MU * float(sca.p.max())
    assert float(vec.omega1[-1]) == pytest.approx(float(sca.omega1[-1]), rel=2e-3)
    assert_contact_laws(vec)


def test_load_along_x2_is_the_transposed_solution():
    """A grid symmetry: T along x2 gives the x1 solution with the axes swapped."""
    a = loading(n=32, direction=(1.0, 0.0), tangential="vector")
    b = loading(n=32, direction=(0.0, 1.0))
    assert "tangential=vector" in b.attrs["models"]
    np.testing.assert_allclose(b.q2.values, np.swapaxes(a.q1.values, 1, 2),
                               atol=1e-6 * MU * float(a.p.max()))


def test_diagonal_load_gives_the_rotated_solution():
    """T at 45° (vector form, 64 x 64 over 3a): the rigid shift is along the load with the
    magnitude of the x1 case (within 0.5 %), q1 and q2 mirror each other across the
    diagonal, and the stick area matches the x1 case within 3 %."""
    c = np.sqrt(0.5)
    ref = loading(direction=(1.0, 0.0), tangential="vector")
    dia = loading(direction=(c, c))
    om = np.hypot(float(dia.omega1[-1]), float(dia.omega2[-1]))
    assert om == pytest.approx(float(ref.omega1[-1]), rel=5e-3)
    assert float(dia.omega1[-1]) == pytest.approx(float(dia.omega2[-1]), rel=1e-6)
    np.testing.assert_allclose(dia.q2.values, np.swapaxes(dia.q1.values, 1, 2),
                               atol=1e-6 * MU * float(dia.p.max()))
    assert float(dia.stick_area[-1]) == pytest.approx(float(ref.stick_area[-1]), rel=0.03)
    assert_contact_laws(dia)
