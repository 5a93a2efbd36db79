"""The preconditioners' model symbols (contactpipe.solver.symbols) against the grids' own
kernel spectra and the closed forms they come from.

K̂33 ≈ c33 g(σ)/σ and K̂_ab ≈ λ_F g(σ)(δ_ab − ν_e ξ̂_a ξ̂_b)/σ: ν_e is the pair's
effective Poisson ratio, Σ(ν/G) / Σ(1/G) over the two bodies (the in-plane compliance
of each half-space is (1 − ν ξ̂1²)/(G|ξ|), Johnson 1985 §3.2–3.5); the model is checked
on the padded spectra sampled at the unpadded grid's frequencies, square and rectangular
cells.
The filters must be symmetric positive definite for preconditioned CG.
"""
import numpy as np
import pytest

from contactpipe.materials import Body
from contactpipe.solver.operator import ContactOperator, body_spectra, convolver
from contactpipe.solver.symbols import radial_profile, root_laplacian

STEEL, ALUMINIUM = Body("elastic", 210e9, 0.3), Body("elastic", 70e9, 0.33)
GRIDS = [(32, 24, 2e-3, 2e-3), (64, 64, 1.5e-3, 1.5e-3), (48, 40, 2e-3, 2e-3),
         (25, 19, 1e-3, 1e-3)]


def _op(n1, n2, l1, l2, indenter=STEEL, halfspace=ALUMINIUM):
    d1, d2 = l1 / n1, l2 / n2
    s1 = None if indenter is None else body_spectra(indenter, n1, n2, d1, d2)
    return ContactOperator(s1, body_spectra(halfspace, n1, n2, d1, d2), 1.0, 1.0,
                           convolver(n1, n2))


def _shear_modulus(body):
    return body.young / (2.0 * (1.0 + body.poisson))


@pytest.mark.parametrize("grid", GRIDS[:3])
def test_effective_poisson_ratio(grid):
    """ν_e read from K11 in real space = Σ(ν/G) / Σ(1/G) (0.3226 for steel on aluminium)
    within 5e-3 (measured 0.3203 on 32 x 24 cells, 6 cells out; 0.3225 at 64², 16 out);
    a rigid indenter: the half-space's own ν, 0.33."""
    g1, g2 = _shear_modulus(STEEL), _shear_modulus(ALUMINIUM)
    expected = (STEEL.poisson / g1 + ALUMINIUM.poisson / g2) / (1.0 / g1 + 1.0 / g2)
    assert _op(*grid)._plane().nu == pytest.approx(expected, abs=5e-3)
    assert _op(*grid, indenter=None)._plane().nu == pytest.approx(0.33, abs=5e-3)


@pytest.mark.parametrize("grid", GRIDS[:3])
def test_model_matches_the_sampled_spectra(grid):
    """The model symbols against the padded K11, K22 (along x1, x2) and K33 spectra at the
    unpadded grid's frequencies (the zero mode left out): between 0.9 and 1.1 from the
    10th to the 90th percentile, median within 3 % (measured 0.92-1.08, medians
    1.000-1.014; the isotropic λ/σ of before: 0.80-1.29, medians up to 1.14)."""
    op = _op(*grid)
    conv, sigma, g, plane = op.conv, op._root_laplacian(), op._radial(), op._plane()
    m = conv.m1 * conv.m2
    models = {"11": plane.lam * g * plane.along((1.0, 0.0)) / sigma,
              "22": plane.lam * g * plane.along((0.0, 1.0)) / sigma,
              "33": op.corner("33") * g / sigma}
    for key, model in models.items():
        ratio = (np.real(op.k[key])[::2, ::2] * m / model).ravel()[1:]
        lo, mid, hi = np.percentile(ratio, [10, 50, 90])
        assert 0.9 < lo and hi < 1.1 and abs(mid - 1.0) < 0.03, (key, lo, mid, hi)


def test_radial_profile_of_an_exact_power_law():
    """A spectrum that is exactly c/σ has g = 1 everywhere (to rounding); a spectrum
    scaled by 1.2 below half the finest σ and 1 above it has g 1.2 at the lowest ring and
    1 at the corner; a grid too small for rings of four modes gives ones."""
    sigma = root_laplacian(40, 32, (1e-5, 1.2e-5))
    c = 3.0e-11
    np.testing.assert_allclose(radial_profile(c / sigma, c, sigma), 1.0, rtol=1e-12)
    step = np.where(sigma < 0.5 * sigma.max(), 1.2, 1.0)
    g = radial_profile(step * c / sigma, c, sigma)
    assert g[sigma <= np.sort(sigma.ravel())[4]].min() == pytest.approx(1.2)
    assert g[sigma == sigma.max()][0] == pytest.approx(1.0)
    tiny = root_laplacian(2, 2, None)
    np.testing.assert_array_equal(radial_profile(c / tiny, c, tiny), 1.0)


@pytest.mark.parametrize("grid", [GRIDS[0], GRIDS[3]])
def test_filters_are_symmetric_positive_definite(grid):
    """⟨u, M v⟩ = ⟨M u, v⟩ to 1e-12 and ⟨v, M v⟩ > 0 for the normal, joint and shear
    filters and the tangential one along a rotated axis, shifted and in bands (one axis
    for a stack, one per stacked field); even and odd grid sizes (the Nyquist lines,
    where the model's odd part ξ̂1 ξ̂2 is set to zero so that the symbol stays even)."""
    op = _op(*grid)
    n1, n2 = grid[:2]
    rng = np.random.default_rng(11)
    u, v = rng.standard_normal((2, 2, n1, n2))
    e = np.array([[np.cos(0.5), np.sin(0.5)], [-np.sin(0.5), np.cos(0.5)]])
    a = op.self_influence("11")
    T, S = op.tangential_preconditioner(), op.shear_preconditioner()
    filters = [op.normal_preconditioner(), op.joint_preconditioner(),
               lambda w: np.stack([S(w[0]), S(w[1])]),
               lambda w: T(w, 0.0, axis=e[0]), lambda w: T(w, np.array([0.0, 3 * a]), axis=e),
               lambda w: T(w, 3 * a, band="high", axis=e),
               lambda w: T(w, 3 * a, band="low", axis=e[1])]
    for M in filters:                   # each maps the stack (2, n1, n2) to its shape
        assert float(np.sum(u * M(v))) == pytest.approx(float(np.sum(M(u) * v)), rel=1e-12)
        for w in (u, v):
            assert float(np.sum(w * M(w))) > 0.0


def test_no_poisson_effect_gives_the_isotropic_filter():
    """With ν = 0 on both bodies the filter along any axis is the isotropic one (to
    1e-13 of its largest value)."""
    body = Body("elastic", 100e9, 0.0)
    op = _op(32, 32, 1e-3, 1e-3, indenter=body, halfspace=body)
    assert op._plane().nu == pytest.approx(0.0, abs=1e-3)
    v = np.random.default_rng(12).standard_normal((32, 32))
    T = op.tangential_preconditioner()
    iso, along = T(v, 0.0), T(v, 0.0, axis=(np.cos(1.0), np.sin(1.0)))
    np.testing.assert_allclose(along, iso, rtol=0, atol=op._plane().nu * np.abs(iso).max()
                               + 1e-13 * np.abs(iso).max())


def test_joint_filter_scales_the_shear_block_alone():
    """ContactOperator.joint_filter(c): the joint preconditioner with its shear block's
    filter times c (the joint solve's 1/μ² folded into the symbol): pressure block the
    same bit for bit, shear block c times it to 1e-14 of its largest value, for c = 100
    (μ = 0.1) and the unscaled filter for c = 1."""
    op = _op(*GRIDS[1])
    n1, n2 = GRIDS[1][:2]
    v = np.random.default_rng(13).standard_normal((2, n1, n2))
    plain = op.joint_preconditioner()(v)
    scaled = op.joint_filter(100.0)(v)
    assert np.array_equal(scaled[0], plain[0])
    assert np.abs(scaled[1] - 100.0 * plain[1]).max() <= 1e-14 * 100.0 * np.abs(plain[1]).max()
    assert np.array_equal(op.joint_filter(1.0)(v), plain)
