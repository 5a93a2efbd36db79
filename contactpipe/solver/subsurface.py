"""Stresses inside an elastic half-space from cell tractions: closed-form kernels, DC-FFT.

Frame and signs
---------------
x1, x2 in the surface, x3 >= 0 the depth into the body; tension > 0. A surface traction
(t1, t2, t3) acts *on* the body: t3 = p > 0 presses it, t1 = q1 pulls its surface along
+x1. Just below a loaded cell the stress is then s13 = -q1, s23 = -q2, s33 = -p (the
material above a depth plane pulls the material below with the force (t1, t2, t3)).
Stresses depend on the Poisson ratio nu only (not on E).

Potentials (Love 1929; Johnson 1985, §3.2)
------------------------------------------
For tractions on the surface, with rho = |x - xi| (xi on the surface) and
``h = ln(rho + x3)`` (harmonic), let ``H = ∫∫ p h``, ``F = ∫∫ q1 h``, ``G = ∫∫ q2 h`` and
``F1 = ∫∫ q1 Omega``, ``G1 = ∫∫ q2 Omega`` with ``Omega = x3 ln(rho + x3) - rho`` (also
harmonic, ∂Omega/∂x3 = h). Johnson's displacements (his eq. 3.7) put into Hooke's law
give, with subscripts for derivatives, z = x3 and 2 pi in front of every bracket:

=========  ============================================  ===========================================
           pressure p                                    shear q1 (q2: exchange 1 and 2)
=========  ============================================  ===========================================
2pi s11    2nu H_zz - (1-2nu) H_xx - z H_xxz             2(1+nu) F_xz + 2nu F1_xxx - z F_xxx
2pi s22    2nu H_zz - (1-2nu) H_yy - z H_yyz             2nu F_xz + 2nu F1_xyy - z F_xyy
2pi s33    H_zz - z H_zzz                                -z F_xzz
2pi s12    -(1-2nu) H_xy - z H_xyz                       F_yz + 2nu F1_xxy - z F_xxy
2pi s13    -z H_xzz                                      F_zz - z F_xxz
2pi s23    -z H_yzz                                      -z F_xyz
=========  ============================================  ===========================================

(for a point force, H = P h, they reduce to Boussinesq's and Cerruti's stresses, which
:func:`point_force_stress` gives in the usual form, independently, for the tests).

Rectangle integrals
-------------------
For a uniform unit traction on the cell [-a, a] x [-b, b], every derivative above with at
least one x and one y is the corner sum ``C[f] = f(x+a, y+b) - f(x+a, y-b) - f(x-a, y+b)
+ f(x-a, y-b)`` of an elementary function f(X, Y, z) (X = x - xi, Y = y - eta,
R = sqrt(X^2 + Y^2 + z^2)); the others follow from the harmonicity of h and Omega
(H_xx + H_yy + H_zz = 0) or from one integral in Y:

================  ===========================================  ==============================
derivative        f in C[f]                                    why
================  ===========================================  ==============================
H_xy              ln(R + z)                                    f_XY = h
H_xyz             1/R                                          h_z = 1/R
H_zz              -atan(X Y / (z R))                           ∫∫ -z/R^3 (solid angle)
H_xx              atan[X Y (R - z) / (X^2 R + z Y^2)]          ∫ X / (R (R+z)) dY
H_yy              atan[X Y (R - z) / (Y^2 R + z X^2)]          (the same, X <-> Y)
H_xxz, H_yyz      -X Y / ((X^2 + z^2) R), -X Y / ((Y^2 + z^2) R)   ∫ -X/R^3 dY
H_xzz, H_yzz      -z Y / ((X^2 + z^2) R), -z X / ((Y^2 + z^2) R)   ∫ -z/R^3 dY
F_xz, F_yz        ln(Y + R), ln(X + R)                         ∫ 1/R dY
F_xxy, F_xyy      X / (R (R+z)), Y / (R (R+z))                 h_X, h_Y
F1_xxy, F1_xyy    -X / (R + z), -Y / (R + z)                   Omega_X, Omega_Y
F_xxx             -F_xyy - F_xzz                               harmonic
F1_xxx            Y / (R + z) - ln(Y + R)                      -F1_xyy - F_xz
================  ===========================================  ==============================

(F = H, F1 = H1 as functions of position: one geometry, another traction.) Functions of
X alone or Y alone cancel in a corner sum and are dropped. ``atan(u/v)`` with v > 0 is
evaluated as ``arctan2(u, v)``; at z = 0 it is continuous and takes its limits
(``atan(XY/(zR)) -> ±pi/2``). ``R - z`` is computed as ``(X^2 + Y^2)/(R + z)`` and
``ln(Y + R)`` as ``ln((X^2 + z^2)/(R - Y))`` for Y < 0, to avoid cancellation.

At the surface (z = 0) the stresses jump at the cell edges (s33 = -p inside, 0 outside)
and the shear terms grow like ln at the edges: DC-FFT evaluates them at cell centres,
which never lie on an edge.

DC-FFT per depth
----------------
At one depth the stress on the grid is a 2-D linear convolution of the cell tractions
with these kernels, computed by :class:`contactpipe.solver.convolution.Convolver` on the
zero-padded 2N1 x 2N2 grid. Each kernel is even or odd in x1 and in x2, so its spectrum is
purely real (even-even, odd-odd) or purely imaginary (odd-even): it is stored as one real
array. Cost per instant and depth: one inverse transform per stress component (6), plus
one forward transform per non-zero traction component, shared by every depth.

References
----------
.. [1] A. E. H. Love, "The stress produced in a semi-infinite solid by pressure on part
   of the boundary", Phil. Trans. R. Soc. A 228 (1929) 377-420. doi:10.1098/rsta.1929.0009
.. [2] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, §3.2-3.4.
   doi:10.1017/CBO9781139171731
.. [3] S. Liu, Q. Wang, "Studying contact stress fields caused by surface tractions with a
   discrete convolution and fast Fourier transform algorithm", J. Tribol. 124 (2002)
   36-45. doi:10.1115/1.1401017
.. [4] J. C. Jaeger, N. G. W. Cook, R. W. Zimmerman, *Fundamentals of Rock Mechanics*,
   4th ed., Blackwell, 2007, §13.4 (Cerruti's stresses in Cartesian form).
"""
from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from .convolution import Convolver
from .periodic_stress import periodic_depth_spectra

__all__ = ["TRACTIONS", "COMPONENTS", "cell_stress", "point_force_stress", "depth_kernels",
           "DepthSpectra", "SubsurfaceOperator", "von_mises", "SPECTRA_CACHE_BYTES"]

#: Traction components in the body's frame: shear along x1, x2, pressure along x3.
TRACTIONS = ("q1", "q2", "p")
#: Stress components, in this order everywhere.
COMPONENTS = ("s11", "s22", "s33", "s12", "s13", "s23")
#: Upper bound of the process-wide cache of depth spectra [bytes].
SPECTRA_CACHE_BYTES = 256 * 2 ** 20

_TWO_PI = 2.0 * np.pi

# Parity of each kernel in (x1, x2): +1 even, -1 odd. The pressure gives the parities of a
# scalar load; a shear along 1 flips the x1 parity, a shear along 2 the x2 parity.
_BASE_PARITY = {"s11": (1, 1), "s22": (1, 1), "s33": (1, 1), "s12": (-1, -1),
                "s13": (-1, 1), "s23": (1, -1)}
_FLIP = {"p": (1, 1), "q1": (-1, 1), "q2": (1, -1)}
PARITY = {(t, c): (_BASE_PARITY[c][0] * _FLIP[t][0], _BASE_PARITY[c][1] * _FLIP[t][1])
          for t in TRACTIONS for c in COMPONENTS}


# --------------------------------------------------------------------------- corner terms

def _log_y_plus_r(x, y, z, r):
    """ln(Y + R) without cancellation for Y < 0 (X^2 + z^2 > 0 assumed there)."""
    pos = y >= 0.0
    num = np.where(pos, y + r, x * x + z * z)
    den = np.where(pos, 1.0, r - y)
    return np.log(num / den)


def _corner_terms(x, y, z):
    """The elementary functions of the corner sums at one corner (X, Y) and depth z."""
    r = np.sqrt(x * x + y * y + z * z)
    rz = r + z
    xy = x * y
    r_minus_z = (x * x + y * y) / np.where(rz > 0.0, rz, 1.0)
    xz2 = x * x + z * z
    yz2 = y * y + z * z
    safe_xz2 = np.where(xz2 > 0.0, xz2, 1.0)
    safe_yz2 = np.where(yz2 > 0.0, yz2, 1.0)
    safe_r = np.where(r > 0.0, r, 1.0)
    safe_rz = np.where(rz > 0.0, rz, 1.0)
    return {
        "Hxy": np.log(safe_rz),
        "Hxyz": 1.0 / safe_r,
        "Hzz": -np.arctan2(xy, z * r),
        "Hxx": np.arctan2(xy * r_minus_z, x * x * r + z * y * y),
        "Hyy": np.arctan2(xy * r_minus_z, y * y * r + z * x * x),
        "Hxxz": -xy / (safe_xz2 * safe_r),
        "Hyyz": -xy / (safe_yz2 * safe_r),
        "Hxzz": -z * y / (safe_xz2 * safe_r),
        "Hyzz": -z * x / (safe_yz2 * safe_r),
        "Fxz": _log_y_plus_r(x, y, z, r),
        "Fyz": _log_y_plus_r(y, x, z, r),
        "Ex": x / (safe_r * safe_rz),
        "Ey": y / (safe_r * safe_rz),
        "Ox": x / safe_rz,
        "Oy": y / safe_rz,
    }


def _corner_sums(x1, x2, z, a, b):
    """Corner sums C[f] of every elementary function for the cell [-a, a] x [-b, b]."""
    out = None
    for sx, big_x in ((1.0, x1 + a), (-1.0, x1 - a)):
        for sy, big_y in ((1.0, x2 + b), (-1.0, x2 - b)):
            terms = _corner_terms(big_x, big_y, z)
            s = sx * sy
            if out is None:
                out = {k: s * v for k, v in terms.items()}
            else:
                for k, v in terms.items():
                    out[k] += s * v
    return out


def _stresses_from_sums(c, z, nu):
    """Stress components of the three unit tractions from the corner sums (module table)."""
    k = 1.0 / _TWO_PI
    hzz, hxx, hyy = c["Hzz"], c["Hxx"], c["Hyy"]
    hzzz = -c["Hxxz"] - c["Hyyz"]
    zt = 0.0 if z == 0.0 else z        # z times a finite term
    s_p = {
        "s11": k * (2 * nu * hzz - (1 - 2 * nu) * hxx - zt * c["Hxxz"]),
        "s22": k * (2 * nu * hzz - (1 - 2 * nu) * hyy - zt * c["Hyyz"]),
        "s33": k * (hzz - zt * hzzz),
        "s12": k * (-(1 - 2 * nu) * c["Hxy"] - zt * c["Hxyz"]),
        "s13": -k * zt * c["Hxzz"],
        "s23": -k * zt * c["Hyzz"],
    }
    fxxx = -c["Ey"] - c["Hxzz"]
    gyyy = -c["Ex"] - c["Hyzz"]
    s_q1 = {
        "s11": k * (2 * c["Fxz"] + 2 * nu * c["Oy"] - zt * fxxx),
        "s22": k * (2 * nu * c["Fxz"] - 2 * nu * c["Oy"] - zt * c["Ey"]),
        "s33": s_p["s13"],
        "s12": k * (c["Fyz"] - 2 * nu * c["Ox"] - zt * c["Ex"]),
        "s13": k * (hzz - zt * c["Hxxz"]),
        "s23": -k * zt * c["Hxyz"],
    }
    s_q2 = {
        "s11": k * (2 * nu * c["Fyz"] - 2 * nu * c["Ox"] - zt * c["Ex"]),
        "s22": k * (2 * c["Fyz"] + 2 * nu * c["Ox"] - zt * gyyy),
        "s33": s_p["s23"],
        "s12": k * (c["Fxz"] - 2 * nu * c["Oy"] - zt * c["Ey"]),
        "s13": s_q1["s23"],
        "s23": k * (hzz - zt * c["Hyyz"]),
    }
    return {"q1": s_q1, "q2": s_q2, "p": s_p}


def cell_stress(x1, x2, x3, d1, d2, poisson):
    """Stress at depth from uniform unit tractions on one rectangular cell (closed form).

    Parameters
    ----------
    x1, x2 : array_like
        Field point minus cell centre, in the surface plane [m]; broadcastable.
    x3 : float
        Depth of the field point into the body [m], >= 0. At x3 = 0 the field is
        finite except on the cell's edges (where it jumps, and the shear terms diverge
        logarithmically); evaluate it off the edges.
    d1, d2 : float
        Cell sides along x1 and x2 [m].
    poisson : float
        Poisson ratio nu [1], 0 <= nu <= 0.5.

    Returns
    -------
    dict
        ``out[t][c]`` for traction t in :data:`TRACTIONS` (unit traction [Pa] along x1,
        x2, or a unit pressure along x3) and component c in :data:`COMPONENTS`: the
        stress per unit traction [Pa/Pa], tension > 0, float64 arrays of the broadcast
        shape.
    """
    x1 = np.asarray(x1, dtype=np.float64)
    x2 = np.asarray(x2, dtype=np.float64)
    x1, x2 = np.broadcast_arrays(x1, x2)
    z = float(x3)
    if not z >= 0.0:
        raise ValueError(f"x3 = {x3!r}: the depth must be >= 0 [m]")
    sums = _corner_sums(x1, x2, z, 0.5 * float(d1), 0.5 * float(d2))
    return _stresses_from_sums(sums, z, float(poisson))


def point_force_stress(x1, x2, x3, poisson):
    """Boussinesq's and Cerruti's stresses of unit point forces at the surface origin.

    The literature's forms, independent of the potentials used by :func:`cell_stress`
    (Johnson 1985 eq. 3.22 for the normal force, in cylindrical components rotated here
    to Cartesian; Jaeger, Cook & Zimmerman 2007 §13.4 for the tangential force, with
    their compression-positive signs turned to tension > 0). Used to check the kernels.

    Parameters
    ----------
    x1, x2 : array_like
        Field point in the surface plane [m], broadcastable.
    x3 : float or array_like
        Depth [m], > 0 (the fields are singular at the point of application).
    poisson : float
        Poisson ratio [1].

    Returns
    -------
    dict
        ``out[t][c]`` [Pa/N] as :func:`cell_stress`: t = "p" a unit normal force pressing
        the body, "q1" / "q2" a unit tangential force along x1 / x2.
    """
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x1, x2, x3)))
    nu = float(poisson)
    r2 = x * x + y * y
    rho = np.sqrt(r2 + z * z)
    # Boussinesq (Johnson eq. 3.22): sigma_r, sigma_theta, tau_rz rotated to Cartesian as
    # s11 = st + x^2 D, s22 = st + y^2 D, s12 = x y D with D = (sr - st)/r^2, using
    # 1 - z/rho = r^2/(rho (rho + z)) so that the axis r = 0 needs no limit.
    k = 1 - 2 * nu
    rz = rho + z
    st = -k * (1 / (rho * rz) - z / rho ** 3) / _TWO_PI
    dd = (k * (2 * rho + z) / (rho ** 3 * rz ** 2) - 3 * z / rho ** 5) / _TWO_PI
    normal = {"s11": st + x * x * dd, "s22": st + y * y * dd,
              "s33": -3 * z ** 3 / (_TWO_PI * rho ** 5), "s12": x * y * dd,
              "s13": -3 * x * z * z / (_TWO_PI * rho ** 5),
              "s23": -3 * y * z * z / (_TWO_PI * rho ** 5)}

    def cerruti(u, v):
        """Stresses of a unit force along u (the other in-plane axis v)."""
        rz = rho + z
        k = 1 - 2 * nu
        s_uu = (-3 * u ** 3 / rho ** 5 + k * u * (rho ** 2 - v * v) / (rho ** 3 * rz ** 2)
                - 2 * k * u * v * v / (rho ** 2 * rz ** 3)) / _TWO_PI
        s_vv = (-3 * u * v * v / rho ** 5 + k * u * (3 * rho ** 2 - u * u) / (rho ** 3 * rz ** 2)
                - 2 * k * u ** 3 / (rho ** 2 * rz ** 3)) / _TWO_PI
        s_uv = (-3 * u * u * v / rho ** 5 + k * v * (u * u - rho ** 2) / (rho ** 3 * rz ** 2)
                + 2 * k * u * u * v / (rho ** 2 * rz ** 3)) / _TWO_PI
        return {"uu": s_uu, "vv": s_vv, "uv": s_uv,
                "zz": -3 * u * z * z / (_TWO_PI * rho ** 5),
                "uz": -3 * u * u * z / (_TWO_PI * rho ** 5),
                "vz": -3 * u * v * z / (_TWO_PI * rho ** 5)}

    c_1 = cerruti(x, y)
    c_2 = cerruti(y, x)
    q1 = {"s11": c_1["uu"], "s22": c_1["vv"], "s33": c_1["zz"], "s12": c_1["uv"],
          "s13": c_1["uz"], "s23": c_1["vz"]}
    q2 = {"s11": c_2["vv"], "s22": c_2["uu"], "s33": c_2["zz"], "s12": c_2["uv"],
          "s13": c_2["vz"], "s23": c_2["uz"]}
    return {"q1": q1, "q2": q2, "p": normal}


def von_mises(s11, s22, s33, s12, s13, s23):
    """Von Mises equivalent stress [Pa] of the six components [Pa] (any shapes)."""
    return np.sqrt(0.5 * ((s11 - s22) ** 2 + (s22 - s33) ** 2 + (s33 - s11) ** 2)
                   + 3.0 * (s12 * s12 + s13 * s13 + s23 * s23))


# --------------------------------------------------------------------------- DC-FFT kernels

def _wraparound(quadrant, p1, p2):
    """A kernel given on the offsets >= 0 (n1 x n2) laid out on the 2n1 x 2n2 grid.

    Offset n1 (and n2) is no physical offset: it stays 0. The other quadrants follow
    from the parities p1, p2 (+1 even, -1 odd), so the layout is exactly (anti)symmetric.
    """
    n1, n2 = quadrant.shape
    k = np.zeros((2 * n1, 2 * n2))
    k[:n1, :n2] = quadrant
    k[n1 + 1:, :n2] = p1 * quadrant[:0:-1, :]
    k[:n1, n2 + 1:] = p2 * quadrant[:, :0:-1]
    k[n1 + 1:, n2 + 1:] = (p1 * p2) * quadrant[:0:-1, :0:-1]
    return k


def depth_kernels(n1, n2, d1, d2, poisson, x3):
    """The 18 stress kernels of one depth on the zero-padded DC-FFT grid.

    Parameters
    ----------
    n1, n2 : int
        Cells along x1, x2.
    d1, d2 : float
        Cell sides [m].
    poisson : float
        Poisson ratio [1].
    x3 : float
        Depth [m], >= 0.

    Returns
    -------
    dict
        ``kernels[(t, c)]`` [Pa/Pa], shape (2 n1, 2 n2), wrap-around order (offset i d1
        at index i < n1, (i - 2 n1) d1 at i > n1; index n1 is 0), for t in
        :data:`TRACTIONS` and c in :data:`COMPONENTS`. Kernels that are equal
        ((q1, s33) = (p, s13), (q2, s33) = (p, s23), (q2, s13) = (q1, s23)) are one array.
    """
    s1 = np.arange(n1) * float(d1)
    s2 = np.arange(n2) * float(d2)
    quad = cell_stress(s1[:, None], s2[None, :], x3, d1, d2, poisson)
    laid = {}                  # equal kernels (the same array in ``quad``) are laid out once
    out = {}
    for t in TRACTIONS:
        for c in COMPONENTS:
            q = quad[t][c]
            if id(q) not in laid:
                laid[id(q)] = _wraparound(q, *PARITY[(t, c)])
            out[(t, c)] = laid[id(q)]
    return out


class DepthSpectra:
    """Kernel spectra of one depth: per (traction, component) a real array and a flag.

    ``khat[(t, c)]`` holds the real part of the scaled spectrum when ``imag[(t, c)]`` is
    False, else its imaginary part (the other part is zero by parity, to rounding).
    """

    __slots__ = ("khat", "imag", "nbytes")

    def __init__(self, conv: Convolver, kernels: dict):
        self.khat = {}
        self.imag = {}
        shared = {}
        for key, kern in kernels.items():
            p1, p2 = PARITY[key]
            imag = p1 * p2 < 0
            if id(kern) not in shared:             # equal kernels share one spectrum
                spec = conv.kernel_spectrum(kern)
                shared[id(kern)] = np.ascontiguousarray(spec.imag if imag else spec.real)
            self.khat[key] = shared[id(kern)]
            self.imag[key] = imag
        self.nbytes = sum(v.nbytes for v in shared.values())

    @classmethod
    def from_spectra(cls, spectra: dict) -> DepthSpectra:
        """The spectra given (complex, scaled; each purely real or purely imaginary by
        its parity), as a periodic grid's come
        (:func:`~contactpipe.solver.periodic_stress.periodic_depth_spectra`)."""
        out = object.__new__(cls)
        out.khat, out.imag = {}, {}
        for key, spec in spectra.items():
            p1, p2 = PARITY[key]
            out.imag[key] = p1 * p2 < 0
            out.khat[key] = np.ascontiguousarray(spec.imag if out.imag[key] else spec.real)
        out.nbytes = sum(v.nbytes for v in out.khat.values())
        return out


class _SpectraCache:
    """Process-wide LRU cache of :class:`DepthSpectra`, bounded in bytes, thread-safe."""

    def __init__(self):
        self._lock = threading.Lock()
        self._items = OrderedDict()
        self.hits = 0
        self.misses = 0

    def get(self, key, make, limit):
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                self.hits += 1
                return self._items[key]
        value = make()                                # outside the lock: may run twice
        with self._lock:
            self.misses += 1
            self._items[key] = value
            total = sum(v.nbytes for v in self._items.values())
            while total > limit and len(self._items) > 1:
                _, old = self._items.popitem(last=False)
                total -= old.nbytes
        return value

    def clear(self):
        with self._lock:
            self._items.clear()
            self.hits = self.misses = 0


_CACHE = _SpectraCache()
_LOCAL = threading.local()


def _thread_convolver(n1, n2, backend, threads, periodic=False):
    """One Convolver per thread and grid (its FFT buffers are not shared between threads)."""
    store = getattr(_LOCAL, "convolvers", None)
    if store is None:
        store = _LOCAL.convolvers = {}
    key = (n1, n2, backend, threads, periodic)
    if key not in store:
        store[key] = Convolver(n1, n2, backend=backend, threads=threads, periodic=periodic)
    return store[key]


class SubsurfaceOperator:
    """Stress at given depths from cell tractions on one grid, by DC-FFT.

    Parameters
    ----------
    n1, n2 : int
        Cells along x1, x2.
    d1, d2 : float
        Cell sides [m].
    poisson : float
        Poisson ratio of the body [1].
    backend, threads :
        Passed to :class:`~contactpipe.solver.convolution.Convolver` (one per thread).
    cache_bytes : int
        Bound of the shared cache of depth spectra [bytes] (default
        :data:`SPECTRA_CACHE_BYTES`). Spectra are keyed by (grid, nu, depth).
    periodic : bool
        The grid is one period of an infinite surface: circular convolution, unpadded,
        with the periodic kernels of :mod:`~contactpipe.solver.periodic_stress`.

    Notes
    -----
    Thread-safe: each thread uses its own FFT engine; the spectra cache is shared.
    """

    def __init__(self, n1, n2, d1, d2, poisson, backend="auto", threads=1,
                 cache_bytes=None, periodic=False):
        self.n1, self.n2 = int(n1), int(n2)
        self.d1, self.d2 = float(d1), float(d2)
        self.poisson = float(poisson)
        self.backend = backend
        self.threads = int(threads)
        self.cache_bytes = SPECTRA_CACHE_BYTES if cache_bytes is None else int(cache_bytes)
        self.periodic = bool(periodic)

    @property
    def conv(self) -> Convolver:
        """This thread's DC-FFT engine for the grid (counts its transforms)."""
        return _thread_convolver(self.n1, self.n2, self.backend, self.threads, self.periodic)

    def spectra(self, x3) -> DepthSpectra:
        """The (cached) kernel spectra of depth ``x3`` [m]."""
        z = float(x3)
        key = (self.n1, self.n2, self.d1, self.d2, self.poisson, z, self.periodic)
        conv = self.conv
        if self.periodic:
            return _CACHE.get(key, lambda: DepthSpectra.from_spectra(periodic_depth_spectra(
                self.n1, self.n2, self.d1, self.d2, self.poisson, z)), self.cache_bytes)
        return _CACHE.get(key, lambda: DepthSpectra(
            conv, depth_kernels(self.n1, self.n2, self.d1, self.d2, self.poisson, z)),
            self.cache_bytes)

    def traction_spectra(self, tractions):
        """Forward spectra of the traction fields (None where absent or all zero).

        Parameters
        ----------
        tractions : dict
            ``{"q1": array or None, "q2": ..., "p": ...}`` [Pa], each (n1, n2), in the
            body's frame.
        """
        conv = self.conv
        out = {}
        for t in TRACTIONS:
            f = tractions.get(t)
            out[t] = None if (f is None or not np.any(f)) else conv.forward(f)
        return out

    def stress(self, specs, x3, out=None):
        """The six stress components at depth ``x3`` from traction spectra.

        Parameters
        ----------
        specs : dict
            :meth:`traction_spectra` of one instant.
        x3 : float
            Depth [m].
        out : ndarray, optional
            (6, n1, n2) array to fill.

        Returns
        -------
        ndarray
            (6, n1, n2) [Pa], components in :data:`COMPONENTS` order. Six inverse
            transforms (none for a component that receives nothing).
        """
        conv = self.conv
        ds = self.spectra(x3)
        if out is None:
            out = np.empty((len(COMPONENTS), self.n1, self.n2))
        acc = np.empty(conv.spec_shape, dtype=complex)
        tmp = np.empty(conv.spec_shape, dtype=complex)
        for i, c in enumerate(COMPONENTS):
            have = False
            for t in TRACTIONS:
                f = specs[t]
                if f is None:
                    continue
                k = ds.khat[(t, c)]
                np.multiply(f, k, out=tmp)
                if ds.imag[(t, c)]:             # i k f: (re, im) -> (-im, re)
                    tmp.real, tmp.imag = -tmp.imag, tmp.real.copy()
                if have:
                    acc += tmp
                else:
                    acc[...] = tmp
                    have = True
            if have:
                conv.inverse(acc, out=out[i])
            else:
                out[i] = 0.0
        return out


def clear_cache():
    """Empty the process-wide cache of depth spectra."""
    _CACHE.clear()


def cache_info() -> dict:
    """Hits, misses, entries and bytes of the depth-spectra cache."""
    with _CACHE._lock:
        return {"hits": _CACHE.hits, "misses": _CACHE.misses, "entries": len(_CACHE._items),
                "bytes": sum(v.nbytes for v in _CACHE._items.values())}
