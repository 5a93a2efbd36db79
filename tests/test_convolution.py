"""DC-FFT convolution against a direct sum; pyFFTW and scipy give the same numbers."""
import numpy as np
import pytest

from contactpipe.solver.convolution import HAVE_PYFFTW, Convolver
from contactpipe.solver.influence import body_kernels


def direct_linear_convolution(kernel_wrap, x):
    """u[i, j] = Σ K(i-l, j-m) x[l, m] with the kernel read from its wrap-around layout."""
    n1, n2 = x.shape
    u = np.zeros_like(x)
    for i in range(n1):
        for j in range(n2):
            for k in range(n1):
                for m in range(n2):
                    u[i, j] += kernel_wrap[(i - k) % (2 * n1), (j - m) % (2 * n2)] * x[k, m]
    return u


@pytest.mark.parametrize("backend", ["scipy"] + (["pyfftw"] if HAVE_PYFFTW else []))
def test_dcfft_equals_direct_sum(backend):
    rng = np.random.default_rng(1)
    n1, n2 = 7, 5                      # odd, unequal sides: catches layout mistakes
    k = body_kernels(n1, n2, 1e-5, 2e-5, 210e9, 0.3)
    x = rng.normal(size=(n1, n2))
    conv = Convolver(n1, n2, backend=backend)
    for comp in ("33", "11", "12", "13", "31"):
        u = conv.convolve(conv.kernel_spectrum(k[comp]), x)
        ref = direct_linear_convolution(k[comp], x)
        np.testing.assert_allclose(u, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_backends_agree_and_count_pairs():
    rng = np.random.default_rng(2)
    n = 32
    k = body_kernels(n, n, 1e-5, 1e-5, 210e9, 0.3)
    a, b = Convolver(n, n, backend="pyfftw"), Convolver(n, n, backend="scipy")
    x = rng.normal(size=(n, n))
    ua = a.convolve(a.kernel_spectrum(k["33"]), x)
    ub = b.convolve(b.kernel_spectrum(k["33"]), x)
    np.testing.assert_allclose(ua, ub, rtol=1e-12, atol=1e-12 * np.abs(ub).max())
    assert a.pairs == 1.0 and b.pairs == 1.0
    # a 2 x 2 block on two inputs: 2 forward + 2 inverse = 2 pairs
    kh = a.kernel_spectrum(k["11"])
    a.reset_counts()
    a.convolve_matrix([[kh, kh], [kh, kh]], [x, x])
    assert a.pairs == 2.0
    # a zero input costs nothing
    a.reset_counts()
    a.convolve_matrix([[kh, kh]], [x, None])
    assert a.pairs == 1.0


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_block_convolution_on_fftw_buffers_agrees_with_scipy():
    """convolve_matrix on pyFFTW's own buffers (each input's spectrum in its own forward
    buffer, the products summed in the inverse plan's input, the transforms pruned of the
    padding) gives scipy's numbers, with a zero input, a vanishing kernel and an output that
    receives nothing, and the same transform counts; then with three live inputs (a third
    buffer made on demand), twice, so that no buffer of one call leaks into the next."""
    rng = np.random.default_rng(3)
    n1, n2 = 12, 10
    k = body_kernels(n1, n2, 1e-5, 2e-5, 210e9, 0.3)
    a, b = Convolver(n1, n2, backend="pyfftw"), Convolver(n1, n2, backend="scipy")
    def spec(c, comp):
        return None if comp is None else c.kernel_spectrum(k[comp])
    layout = [["11", "12", "13"], ["21", None, "23"], [None, None, "33"], [None, "32", None]]
    xs = [rng.normal(size=(n1, n2)), rng.normal(size=(n1, n2)), None]
    ua = a.convolve_matrix([[spec(a, c) for c in row] for row in layout], xs)
    ub = b.convolve_matrix([[spec(b, c) for c in row] for row in layout], xs)
    np.testing.assert_allclose(ua, ub, rtol=1e-12, atol=1e-12 * np.abs(ub).max())
    assert not ua[2].any() and ua[3].any()        # nothing reaches row 2
    assert (a.forward_count, a.inverse_count) == (b.forward_count, b.inverse_count) == (2, 3)
    c = Convolver(n1, n2, backend="pyfftw", threads=2)      # the pruned plans, threaded
    uc = c.convolve_matrix([[spec(c, comp) for comp in row] for row in layout], xs)
    np.testing.assert_allclose(uc, ub, rtol=1e-12, atol=1e-12 * np.abs(ub).max())
    xs3 = [rng.normal(size=(n1, n2)) for _ in range(3)]
    for _ in range(2):
        ua = a.convolve_matrix([[spec(a, c) for c in row] for row in layout], xs3)
        ub = b.convolve_matrix([[spec(b, c) for c in row] for row in layout], xs3)
        np.testing.assert_allclose(ua, ub, rtol=1e-12, atol=1e-12 * np.abs(ub).max())
        xs3 = xs3[::-1]


@pytest.mark.parametrize("backend", ["scipy"] + (["pyfftw"] if HAVE_PYFFTW else []))
def test_periodic_filter_is_the_circular_convolution(backend):
    """The preconditioner's unpadded filter: one field and a stack of two equal the
    circular convolution with the symbol's inverse transform (direct sum, 1e-12), on odd
    unequal sides; each field counts a quarter of an FFT pair."""
    rng = np.random.default_rng(4)
    n1, n2 = 7, 6
    conv = Convolver(n1, n2, backend=backend)
    sigma = rng.uniform(0.5, 2.0, (n1, n2 // 2 + 1)) / (n1 * n2)
    sigma = 0.5 * (sigma + sigma[-np.arange(n1) % n1])    # even in ξ1: a real, even kernel
    kernel = np.fft.irfft2(sigma * (n1 * n2), s=(n1, n2))
    x = rng.normal(size=(2, n1, n2))
    ref = np.zeros_like(x)
    for f in range(2):
        for i in range(n1):
            for j in range(n2):
                ref[f, i, j] = sum(kernel[(i - k) % n1, (j - m) % n2] * x[f, k, m]
                                   for k in range(n1) for m in range(n2))
    scale = np.abs(ref).max()
    np.testing.assert_allclose(conv.periodic_filter(sigma, x[0]), ref[0], atol=1e-12 * scale)
    out = np.empty_like(x)
    conv.periodic_filter(sigma, x, out=out)
    np.testing.assert_allclose(out, ref, atol=1e-12 * scale)
    assert conv.filtered == 3 and conv.pairs == pytest.approx(0.75)


@pytest.mark.parametrize("backend", ["scipy"] + (["pyfftw"] if HAVE_PYFFTW else []))
def test_block_operator_in_halves_is_the_whole_product(backend):
    """A 3 x 3 block of kernels (the vector joint solve's, 12 x 10 cells) applied in halves:
    the spectra's product, transformed back, is the whole product (to 1e-14 of its
    largest); xᵀ A t and tᵀ A t from the spectra by Parseval's theorem equal the sums
    over the cells (to 1e-13 relative); a zero field costs no forward transform, and the
    inverse transforms are one per output."""
    from contactpipe.solver.blocks import BlockOperator, DirectOperator
    n1, n2 = 12, 10
    conv = Convolver(n1, n2, backend=backend)
    ker = body_kernels(n1, n2, 1e-5, 2e-5, 210e9, 0.3)
    k = {c: conv.kernel_spectrum(v) for c, v in ker.items()}
    A = BlockOperator(conv, [[k["33"], k["31"], k["32"]], [k["13"], k["11"], k["12"]],
                             [k["23"], k["21"], k["22"]]])
    rng = np.random.default_rng(3)
    t, x = rng.normal(size=(2, 3, n1, n2))
    x[0] = 0.0
    At = A(t)
    conv.reset_counts()
    that = A.spectra(t)                   # in the engine's buffers until the next call
    rhat = A.product(that)
    assert A.inner(that, rhat) == pytest.approx(float(np.sum(t * At)), rel=1e-13)
    xhat = A.spectra(x)
    assert xhat[0] is None and conv.forward_count == 5 and conv.inverse_count == 0
    assert A.inner(xhat, rhat) == pytest.approx(float(np.sum(x * At)), rel=1e-13)
    both = A.add(np.zeros_like(At), rhat, -0.5, A.product(xhat))
    assert conv.inverse_count == 3 and conv.forward_count == 5
    exact = -0.5 * At + A(x)
    assert np.abs(both - exact).max() <= 1e-14 * np.abs(exact).max()
    direct = DirectOperator(A)
    assert direct.inner(direct.spectra(t), direct.product(t)) == pytest.approx(
        float(np.sum(t * At)), rel=1e-15)
    np.testing.assert_allclose(direct.add(np.zeros_like(At), At, -0.5, A(x)), exact,
                               rtol=0, atol=1e-14 * np.abs(exact).max())
