"""The vector CG's filter (ContactOperator.tangential_preconditioner) against its definition.

M(v, d) filters v by σ/(λ + d σ), σ the symbol of (−Δ)^½ and λ the tangential block's
finest-mode stiffness: an approximation of (K_t + d I)⁻¹. Checked here: it is symmetric
positive definite (what preconditioned CG needs), its model λ/σ matches the padded K11,
K22 spectra on the grid's own frequencies, and it tends to I/d for a large shift. That it
speeds the vector form up without changing its answer is checked on the coupled instants
(test_coupling.test_preconditioned_vector_passes_reach_the_diagonally_scaled_instants).
Steel on aluminium, 32 x 24 cells of 62.5 x 83.3 µm (rectangular).
"""
import numpy as np
import pytest

from contactpipe.materials import Body
from contactpipe.solver.operator import ContactOperator, body_spectra, convolver

N1, N2 = 32, 24
D1, D2 = 2e-3 / N1, 2e-3 / N2


@pytest.fixture(scope="module")
def op():
    s1 = body_spectra(Body("elastic", 210e9, 0.3), N1, N2, D1, D2)
    s2 = body_spectra(Body("elastic", 70e9, 0.33), N1, N2, D1, D2)
    return ContactOperator(s1, s2, 1.0, 1.0, convolver(N1, N2))


@pytest.mark.parametrize("shift", [0.0, 1.0, 10.0])
def test_symmetric_positive_definite(op, shift):
    """⟨u, M v⟩ = ⟨M u, v⟩ to 1e-12 and ⟨v, M v⟩ > 0, for two stacked fields, with the
    shift d = 0, 1 and 10 self-influences."""
    M = op.tangential_preconditioner()
    d = shift * op.self_influence("11")
    rng = np.random.default_rng(4)
    u, v = rng.standard_normal((2, 2, N1, N2))
    uv, vu = float(np.sum(u * M(v, d))), float(np.sum(M(u, d) * v))
    assert uv == pytest.approx(vu, rel=1e-12)
    for w in (u, v, np.ones((2, N1, N2))):
        assert float(np.sum(w * M(w, d))) > 0.0


def test_model_matches_the_tangential_spectra(op):
    """λ/σ against the mean of the padded K11 and K22 spectra at the unpadded grid's
    frequencies (every other padded one): within 25 % over 80 % of them, median within
    10 % (measured on these rectangular cells 0.98-1.19 between the 10th and 90th
    percentiles; 0.93-1.12, median 1.00, on square cells; the zero mode, where σ is set to
    its smallest other value, left out)."""
    conv = op.conv
    op.tangential_preconditioner()
    sigma, lam = op._derived["precondition_t"]
    k = 0.5 * (np.real(op.k["11"]) + np.real(op.k["22"]))[::2, ::2] * conv.m1 * conv.m2
    ratio = (k * sigma / lam).ravel()[1:]
    lo, mid, hi = np.percentile(ratio, [10, 50, 90])
    assert 0.75 < lo and hi < 1.25 and abs(mid - 1.0) < 0.1


def test_large_shift_tends_to_the_diagonal(op):
    """M(v, d) → v/d as d grows: within 1e-5 of v/d for d = 1e6 λ/σ_min."""
    M = op.tangential_preconditioner()
    sigma, lam = op._derived["precondition_t"]
    d = 1e6 * lam / float(sigma.min())
    v = np.random.default_rng(5).standard_normal((2, N1, N2))
    np.testing.assert_allclose(M(v, d) * d, v, rtol=0, atol=1e-5 * np.abs(v).max())
