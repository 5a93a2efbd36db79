"""The numerical core: plain numpy arrays in, plain arrays out (no xarray, no files).

The paper's three loops, bottom up:

* :mod:`.influence` - influence coefficients of one body and of the pair (eq. 8);
* :mod:`.convolution` - DC-FFT on pyFFTW (scipy.fft fallback), FFT-pair counting;
* :mod:`.operator` - the pair's influence operator on one grid (cached kernel spectra);
* :mod:`.cg` - bound- and force-constrained conjugate gradients (Polonsky-Keer);
* :mod:`.normal`, :mod:`.tangential` - the inner, uncoupled problems (UNC, UTC);
* :mod:`.coupling` - the middle loop (normal <-> tangential) of one instant;
* :mod:`.memory` - the viscoelastic history (Boltzmann sum, eq. 7) as recursions.

The outer loop in time is :mod:`contactpipe.simulation`.
"""
