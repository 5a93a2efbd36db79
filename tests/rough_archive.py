"""A synthetic archive of a rough contact, shaped as the archive's schema (fields over
(time, x1, x2), series over time, the initial gap h0 over (x1, x2)), for the tests of the
rough figure at sizes a test could not afford to solve (512^2 and more)."""
import numpy as np
import xarray as xr

from contactpipe.nomenclature import STATUS_SEPARATED, STATUS_SLIP, STATUS_STICK


def rough_dataset(n=512, steps=6, side=1e-3, seed=0, constant_load=False):
    """An n x n archive of side ``side`` [m]: h0 a smoothed random surface (least value
    0), at each instant the cells with h0 below a rising level in contact, p = E' (level -
    h0) there, stick where p exceeds half its largest value, slip elsewhere in contact;
    contact_area, stick_area and W summed from the cells (W rises unless
    ``constant_load``, when the level stays and a tangential force T1 rises instead)."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n)
    filt = np.exp(-(k[:, None] ** 2 + k[None, :] ** 2) / (2 * 0.02 ** 2))
    z = np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * filt).real
    h0 = (z.max() - z) / np.ptp(z) * 1e-6
    d = side / n
    x = -side / 2 + (np.arange(n) + 0.5) * d
    levels = np.full(steps, 2e-7) if constant_load else np.linspace(0.5e-7, 3e-7, steps)
    p = np.maximum(levels[:, None, None] - h0[None], 0.0) * 2e11
    top = p.reshape(steps, -1).max(axis=1)[:, None, None]
    status = np.where(p > 0, np.where(p > 0.5 * top, STATUS_STICK, STATUS_SLIP),
                      STATUS_SEPARATED).astype(np.int8)
    f3, f1 = ("time", "x1", "x2"), ("time",)
    t = np.linspace(0.1, 1.0, steps)
    T1 = np.linspace(0.0, 1.0, steps) if constant_load else np.zeros(steps)
    return xr.Dataset(
        {"p": (f3, p.astype(np.float32), {"units": "Pa"}),
         "q1": (f3, np.zeros_like(p, np.float32), {"units": "Pa"}),
         "status": (f3, status, {"units": "1"}),
         "h0": (("x1", "x2"), h0, {"units": "m"}),
         "W": (f1, p.sum(axis=(1, 2)) * d * d, {"units": "N"}),
         "T1": (f1, T1, {"units": "N"}), "omega1": (f1, T1 * 1e-9, {"units": "m"}),
         "contact_area": (f1, (status > 0).sum(axis=(1, 2)) * d * d, {"units": "m2"}),
         "stick_area": (f1, (status == STATUS_STICK).sum(axis=(1, 2)) * d * d,
                        {"units": "m2"})},
        coords={"time": (f1, t, {"units": "s"}), "x1": ("x1", x, {"units": "m"}),
                "x2": ("x2", x, {"units": "m"})},
        attrs={"title": f"synthetic-rough-{n}"})
