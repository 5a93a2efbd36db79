"""The accelerated normal solve: preconditioned CG and the multilevel (coarse-grid) start.

Each acceleration must give the plain Polonsky-Keer solver's answer to within the
tolerance; the pieces are checked against their definitions (Galerkin coarse operator,
bilinear prolongation, a symmetric positive definite preconditioner). Iteration counts
and FFT pairs are benchmark figures (benchmarks/vs_tamaas.py), not asserted here.
"""
import numpy as np
import pytest
from helpers import A_HERTZ, P0_HERTZ, R, W

from contactpipe.materials import Body
from contactpipe.scene.geometry import ellipsoid_gap, sphere_gap
from contactpipe.solver.normal import NormalControl, prolong, restrict, solve_normal
from contactpipe.solver.operator import ContactOperator, body_spectra, convolver

STEEL = Body("elastic", 210e9, 0.3)


def operator(n1, n2, span1, span2):
    """(op, x1, x2, cell area) of an n1 x n2 steel-on-steel grid over span1 x span2 [m]."""
    d1, d2 = span1 / n1, span2 / n2
    x1 = (np.arange(n1) + 0.5) * d1 - span1 / 2
    x2 = (np.arange(n2) + 0.5) * d2 - span2 / 2
    s = body_spectra(STEEL, n1, n2, d1, d2)
    return ContactOperator(s, s, 1.0, 1.0, convolver(n1, n2)), x1, x2, d1 * d2


def both(op, gap, cell, tol=1e-10, control=None):
    """(plain, accelerated) solutions from zero traction."""
    zero = np.zeros_like(gap)
    plain = solve_normal(op, gap, W, cell, zero, tol, 5000, control=control,
                         precondition=False, multilevel=False)
    fast = solve_normal(op, gap, W, cell, zero, tol, 5000, control=control)
    return plain, fast


@pytest.mark.parametrize("n", [64, 128])
def test_hertz_same_pressure_as_the_plain_solver(n):
    """Hertz over 4a, tolerance 1e-10: the accelerated solve (preconditioned, multilevel
    start from 16²) gives the plain solver's pressure within 1e-8 p0 and its approach within
    1e-9 (measured 1.6e-10 / 2.9e-10 p0 and 2.4e-13 / 4.2e-13 at 64² / 128²)."""
    op, x1, x2, cell = operator(n, n, 4 * A_HERTZ, 4 * A_HERTZ)
    op.conv.reset_counts()
    plain, fast = both(op, sphere_gap(x1, x2, R), cell)
    assert plain.converged and fast.converged
    assert np.abs(fast.p - plain.p).max() < 1e-8 * P0_HERTZ
    assert fast.omega3 == pytest.approx(plain.omega3, rel=1e-9)
    assert fast.p.sum() * cell == pytest.approx(W, rel=1e-12)


def test_rectangular_cells_same_pressure():
    """Ellipsoid R = (18, 6) mm on 64 x 48 cells over 3a1 x 3a2 (cells 1.55 : 1, one
    coarse grid of 32 x 24): the plain solver's pressure within 1e-8 of its peak
    (measured 1.4e-10)."""
    from contactpipe.analytic import hertz_ellipsoid
    a1, a2 = hertz_ellipsoid(W, (0.018, 0.006), 1 / (2 * (1 - 0.3 ** 2) / 210e9)).semi_axes
    op, x1, x2, cell = operator(64, 48, 3 * a1, 3 * a2)
    plain, fast = both(op, ellipsoid_gap(x1, x2, (0.018, 0.006)), cell)
    assert plain.converged and fast.converged
    assert np.abs(fast.p - plain.p).max() < 1e-8 * plain.p.max()


def test_moment_control_same_pressure():
    """W and M1 force-controlled (M1 = 0.1 a W), φ2 held at 0, 64²: the accelerated solve
    (constraint rows, coarse rows from the coarse cell centres) gives the plain solver's
    pressure within 1e-8 p0 and its tilt φ1 within 1e-7 (measured 2.1e-10, 9e-13)."""
    op, x1, x2, cell = operator(64, 64, 4 * A_HERTZ, 4 * A_HERTZ)
    ctl = NormalControl(np.array([W, 0.1 * A_HERTZ * W, np.nan]),
                        np.array([np.nan, np.nan, 0.0]), x1, x2)
    plain, fast = both(op, sphere_gap(x1, x2, R), cell, control=ctl)
    assert plain.converged and fast.converged
    assert np.abs(fast.p - plain.p).max() < 1e-8 * P0_HERTZ
    assert fast.phi[0] == pytest.approx(plain.phi[0], rel=1e-7)
    X2 = np.meshgrid(x1, x2, indexing="ij")[1]
    assert float((fast.p * X2).sum() * cell) == pytest.approx(0.1 * A_HERTZ * W, rel=1e-9)


def test_warm_start_skips_the_coarse_grid():
    """A warm-started solve spends no coarse-grid work; a cold one charges it to the fine
    grid's pair count at a quarter per level, as the preconditioner's unpadded filters
    are (so the count exceeds the padded transforms)."""
    op, x1, x2, cell = operator(64, 64, 4 * A_HERTZ, 4 * A_HERTZ)
    gap = sphere_gap(x1, x2, R)
    conv = op.conv
    conv.reset_counts()
    cold = solve_normal(op, gap, W, cell, np.zeros_like(gap), 1e-10, 5000)
    assert conv.charged > 0.0
    assert conv.pairs == pytest.approx(0.5 * (conv.forward_count + conv.inverse_count)
                                       + conv.charged + 0.25 * conv.filtered)
    conv.reset_counts()
    warm = solve_normal(op, gap, W, cell, cold.p, 1e-10, 5000, Ap0=cold.Ap)
    assert conv.charged == 0.0 and warm.converged


def test_coarse_operator_is_galerkin():
    """K_c x_c = R K P x_c to rounding (1e-12 of the largest value): P the piecewise
    constant injection onto the fine grid, R the 2 x 2 mean; 32 x 24 cells."""
    op, *_ = operator(32, 24, 1e-3, 0.8e-3)
    coarse = op.coarse_normal()
    xc = np.random.default_rng(0).uniform(0.0, 1.0, (16, 12))
    fine = np.repeat(np.repeat(xc, 2, 0), 2, 1)
    expected = restrict(op.normal(fine))
    np.testing.assert_allclose(coarse.normal(xc), expected, rtol=0,
                               atol=1e-12 * np.abs(expected).max())
    assert operator(31, 24, 1e-3, 1e-3)[0].coarse_normal() is None


def test_prolong_and_restrict_of_linear_fields():
    """A positive linear field: restriction gives its values at the coarse cell centres,
    prolongation its values at the fine cell centres away from the edge rows (exact to
    rounding); a coarse cell without pressure gives its four fine cells none."""
    xf = (np.arange(16) + 0.5) / 16
    xc = (np.arange(8) + 0.5) / 8
    lin = lambda u, v: 2.0 + u[:, None] + 3.0 * v[None, :]         # noqa: E731
    np.testing.assert_allclose(restrict(lin(xf, xf)), lin(xc, xc), rtol=1e-14)
    np.testing.assert_allclose(prolong(lin(xc, xc))[1:-1, 1:-1], lin(xf, xf)[1:-1, 1:-1],
                               rtol=1e-14)
    a = lin(xc, xc)
    a[2, 3] = 0.0
    assert np.all(prolong(a)[4:6, 6:8] == 0.0)


def test_preconditioner_is_symmetric_positive_definite():
    """⟨u, M v⟩ = ⟨M u, v⟩ to 1e-12 and ⟨v, M v⟩ > 0 for random fields, rectangular cells."""
    op, *_ = operator(24, 16, 1e-3, 0.5e-3)
    M = op.normal_preconditioner()
    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, 24, 16))
    uv, vu = float(np.sum(u * M(v))), float(np.sum(M(u) * v))
    assert uv == pytest.approx(vu, rel=1e-12)
    for w in (u, v, np.ones((24, 16))):
        assert float(np.sum(w * M(w))) > 0.0
