"""Tests of contactpipe.post.fatigue: multiaxial fatigue criteria over a cycle.

Each criterion is checked on histories done by hand (sinusoidal uniaxial and torsional
stress at a point, with and without a mean), the minimum circumscribed ball against an
independent optimiser and against paths whose ball is known, and the field reduction
(maximum and where it is) on a stress field built for the purpose.
"""
import math

import numpy as np
import pytest
import xarray as xr
from scipy.optimize import minimize

import contactpipe as cp
from contactpipe.post.fatigue import (
    CRITERIA,
    deviatoric_coordinates,
    longest_chord,
    min_ball,
    plane_normals,
)

COMPONENTS = ("s11", "s22", "s33", "s12", "s13", "s23")
F_LIMIT, T_LIMIT = 450e6, 300e6          # fully reversed bending and torsion limits [Pa]
E = 210e9
T = np.linspace(0.0, 2 * np.pi, 73)     # one period, 5 degree steps


def history(**components):
    """A (nt, 6) history from component arrays (missing components are 0)."""
    h = np.zeros((len(T), 6))
    for name, values in components.items():
        h[:, COMPONENTS.index(name)] = values
    return h


def field(h, nu=0.3, peak=None):
    """A stress dataset holding the history h at every point of a small grid; with
    ``peak = (k, i, j)`` that point gets 1.5 h (so it is the maximum of any criterion)."""
    nt = h.shape[0]
    shape = (nt, 3, 4, 5)
    data = {}
    for m, name in enumerate(COMPONENTS):
        a = h[:, m].reshape(nt, 1, 1, 1) * np.ones(shape)
        if peak is not None:
            a[(slice(None),) + tuple(peak)] *= 1.5
        data[name] = (("time", "x3", "x1", "x2"), a, {"units": "Pa"})
    return xr.Dataset(data, coords={"time": np.arange(nt) * 0.01, "x3": [0.0, 1e-4, 2e-4],
                                    "x1": [-2e-4, -1e-4, 0.0, 1e-4],
                                    "x2": [-2e-4, -1e-4, 0.0, 1e-4, 2e-4]},
                      attrs={"poisson": nu, "body": "halfspace"})


LIMITS = {"torsion_limit": T_LIMIT, "bending_limit": F_LIMIT}


@pytest.mark.parametrize("criterion", ["crossland", "dang_van"])
@pytest.mark.parametrize("case", ["bending", "torsion"])
def test_fatigue_limits_give_index_one(criterion, case):
    """Fully reversed uniaxial stress at f_-1, or shear at t_-1: index 1 (1e-9): the two
    conditions that define the constants of Crossland and of Dang Van."""
    h = history(s11=F_LIMIT * np.sin(T)) if case == "bending" else \
        history(s12=T_LIMIT * np.sin(T))
    fi = cp.fatigue(field(h), criterion, **LIMITS)
    main = fi.attrs["criterion_field"]
    assert np.allclose(fi[main].values, 1.0, rtol=1e-9, atol=0)
    assert float(fi["maximum"]) == pytest.approx(1.0, rel=1e-9)


def test_crossland_with_a_mean_stress():
    """s11 = sm + sa sin: sqrt(J2,a) = sa/sqrt 3, sigma_h,max = (sm + sa)/3, alpha = 3t/f -
    sqrt 3; index (sa/sqrt 3 + alpha (sm + sa)/3)/t (1e-9)."""
    sm, sa = 100e6, 200e6
    fi = cp.fatigue(field(history(s11=sm + sa * np.sin(T))), "crossland", **LIMITS)
    alpha = 3 * T_LIMIT / F_LIMIT - math.sqrt(3)
    assert float(fi["sqrt_j2_amplitude"][0, 0, 0]) == pytest.approx(sa / math.sqrt(3), rel=1e-9)
    assert float(fi["hydrostatic_max"][0, 0, 0]) == pytest.approx((sm + sa) / 3, rel=1e-12)
    want = (sa / math.sqrt(3) + alpha * (sm + sa) / 3) / T_LIMIT
    assert float(fi["maximum"]) == pytest.approx(want, rel=1e-9)


def test_dang_van_with_a_mean_stress():
    """s11 = sm + sa sin: the mesoscopic deviator is that of sa sin (the centre of the
    path is the mean's deviator), tau = |sa sin|/2, sigma_h = (sm + sa sin)/3; the largest
    tau + a sigma_h (a = 3t/f - 3/2 > 0) is at sin = 1: (sa/2 + a (sm + sa)/3)/t."""
    sm, sa = 100e6, 200e6
    fi = cp.fatigue(field(history(s11=sm + sa * np.sin(T))), "dang_van", **LIMITS)
    a = 3 * T_LIMIT / F_LIMIT - 1.5
    assert float(fi["maximum"]) == pytest.approx((sa / 2 + a * (sm + sa) / 3) / T_LIMIT,
                                                 rel=1e-9)
    assert float(fi["mesoscopic_shear"][1, 2, 3]) == pytest.approx(sa / 2, rel=1e-9)


def test_out_of_phase_tension_torsion():
    """s11 = s sin, s12 = (s/sqrt 3) cos: a circle in the deviatoric space, sqrt(J2) =
    s/sqrt 3 at every instant; the ball is centred at 0 with radius s/sqrt 3, by the
    minimum ball and by the longest chord alike (1e-9)."""
    s = 300e6
    h = history(s11=s * np.sin(T), s12=s / math.sqrt(3) * np.cos(T))
    for method in ("mcb", "longest_chord"):
        fi = cp.fatigue(field(h), "crossland", shear_amplitude=method, **LIMITS)
        assert float(fi["sqrt_j2_amplitude"][0, 0, 0]) == pytest.approx(s / math.sqrt(3),
                                                                        rel=1e-9)


def test_swt_uniaxial_and_torsion():
    """SWT on the critical plane: uniaxial s11 = sm + sa sin -> (sm + sa) sa / E on the
    plane normal to x1; shear s12 = t sin -> (1 + nu) t^2 / E on the planes at 45° in the
    x1-x2 plane (refined normal within 0.1°)."""
    sm, sa, tau, nu = 100e6, 200e6, 250e6, 0.3
    fi = cp.fatigue(field(history(s11=sm + sa * np.sin(T)), nu=nu), "swt", young=E)
    assert float(fi["maximum"]) == pytest.approx((sm + sa) * sa / E, rel=1e-9)
    assert abs(float(fi["plane_n1"][0, 0, 0])) == pytest.approx(1.0, abs=1e-9)
    assert float(fi["swt_stress"][0, 0, 0]) == pytest.approx(math.sqrt((sm + sa) * sa),
                                                             rel=1e-9)
    fi = cp.fatigue(field(history(s12=tau * np.sin(T)), nu=nu), "swt", young=E)
    assert float(fi["maximum"]) == pytest.approx((1 + nu) * tau ** 2 / E, rel=1e-5)
    n1, n2, n3 = (float(fi[f"plane_n{i}"][0, 0, 0]) for i in (1, 2, 3))
    assert abs(n3) < 2e-3 and abs(abs(n1) - abs(n2)) < 3e-3


def test_swt_compression_only_is_zero():
    """A purely compressive hydrostatic history opens no plane: SWT = 0."""
    p = -np.abs(np.sin(T)) * 1e8
    fi = cp.fatigue(field(history(s11=p, s22=p, s33=p)), "swt", young=E)
    assert float(fi["maximum"]) == 0.0


def test_amplitude_and_mean():
    """Per component (max - min)/2 and (max + min)/2; the von Mises amplitude of a
    proportional history is that of the amplitude tensor."""
    h = history(s11=50e6 + 100e6 * np.sin(T), s22=-20e6 + 40e6 * np.sin(T),
                s13=30e6 * np.sin(T))
    fi = cp.fatigue(field(h), "amplitude")
    assert float(fi["s11_amplitude"][0, 0, 0]) == pytest.approx(100e6, rel=1e-12)
    assert float(fi["s11_mean"][0, 0, 0]) == pytest.approx(50e6, rel=1e-9)
    assert float(fi["s22_mean"][0, 0, 0]) == pytest.approx(-20e6, rel=1e-9)
    a = dict(s11=100e6, s22=40e6, s33=0.0, s12=0.0, s13=30e6, s23=0.0)
    vm = math.sqrt(0.5 * ((a["s11"] - a["s22"]) ** 2 + a["s22"] ** 2 + a["s11"] ** 2)
                   + 3 * a["s13"] ** 2)
    assert float(fi["equivalent_amplitude"][0, 0, 0]) == pytest.approx(vm, rel=1e-9)


def test_maximum_and_where_it_is():
    """The field's largest value and its coordinates (x1, x2, x3) are reported."""
    h = history(s11=F_LIMIT * np.sin(T))
    fi = cp.fatigue(field(h, peak=(1, 2, 3)), "crossland", **LIMITS)
    assert float(fi["maximum"]) == pytest.approx(1.5, rel=1e-9)
    assert float(fi["maximum_x3"]) == 1e-4 and float(fi["maximum_x1"]) == 0.0
    assert float(fi["maximum_x2"]) == 1e-4
    assert fi["crossland_index"].dims == ("x3", "x1", "x2")
    assert fi["maximum_x1"].attrs["units"] == "m"


# --------------------------------------------------------------------------- the ball

def test_min_ball_against_an_optimiser():
    """Random point sets (40 points in 5-D): the certified radius agrees with SLSQP on
    min r^2 s.t. |p_i - c|^2 <= r^2 to 1e-7, is >= half the longest chord and <= it
    times sqrt(2 d/(d + 1)) (Jung)."""
    rng = np.random.default_rng(7)
    P = rng.normal(size=(300, 40, 5)) * rng.uniform(0.1, 10, size=(300, 1, 1)) + 50.0
    c, r = min_ball(P, tolerance=1e-10)
    _, half_chord = longest_chord(P)
    assert np.all(r >= half_chord * (1 - 1e-12))
    assert np.all(r <= half_chord * math.sqrt(2 * 5 / 6) * (1 + 1e-12))
    assert np.all(np.sqrt(((P - c[:, None]) ** 2).sum(-1)).max(1) <= r * (1 + 1e-12))
    for i in range(12):
        cons = {"type": "ineq", "fun": lambda x, Q=P[i]: x[-1] - ((Q - x[:5]) ** 2).sum(1)}
        x0 = np.r_[P[i].mean(0), ((P[i] - P[i].mean(0)) ** 2).sum(1).max()]
        res = minimize(lambda x: x[-1], x0, constraints=[cons], method="SLSQP",
                       options={"ftol": 1e-15, "maxiter": 2000})
        assert math.sqrt(res.x[-1]) == pytest.approx(r[i], rel=1e-7)


def test_min_ball_known_cases():
    """An equilateral triangle (unit circumradius): ball radius 1 centred at its centre,
    longest chord sqrt(3)/2; a segment traversed back and forth: its half length; all
    points equal: radius 0."""
    tri = np.zeros((1, 3, 5))
    tri[0, :, :2] = [[1, 0], [-0.5, math.sqrt(3) / 2], [-0.5, -math.sqrt(3) / 2]]
    c, r = min_ball(tri)
    assert r[0] == pytest.approx(1.0, rel=1e-12) and np.abs(c).max() < 1e-12
    assert longest_chord(tri)[1][0] == pytest.approx(math.sqrt(3) / 2, rel=1e-12)
    seg = np.zeros((1, 9, 5))
    seg[0, :, 2] = 3.0 + 2.0 * np.sin(np.linspace(0, 2 * np.pi, 9))
    c, r = min_ball(seg)
    assert r[0] == pytest.approx(2.0, rel=1e-12) and c[0, 2] == pytest.approx(3.0)
    c, r = min_ball(np.ones((2, 6, 5)))
    assert np.all(r == 0) and np.allclose(c, 1.0)


#: The deviatoric path (5-D, Pa) of a point of a worn gross-slip contact's last loop (the
#: wear-against-cracking study, delta*/delta_gs = 2.5, 32^2, 16 steps, 10^5 cycles): it
#: dwells, so points 1-4, 7-12 and 15-16 are near-copies (40-230 Pa
#: apart, on a radius of 4.4e7 Pa), and the ball's support is points 0, 4 and 8.
DWELLING_PATH = [
    [-43914505.822, 35916304.597, 60983498.644, -164223566.099, 95689018.105],
    [-43888823.048, 35780177.379, 60961060.843, -164300882.626, 95785464.432],
    [-43888814.451, 35780123.291, 60961052.009, -164300918.073, 95785502.557],
    [-43888805.853, 35780069.220, 60961043.178, -164300953.498, 95785540.672],
    [-43888797.254, 35780015.149, 60961034.347, -164300988.922, 95785578.786],
    [-18625453.552, 26455584.111, 44857048.074, -134854307.310, 86442780.773],
    [-1513642.627, 14732594.086, 25822479.449, -119302675.320, 78473612.513],
    [4676598.535, 9800612.698, 17229702.349, -114553905.225, 75676936.903],
    [4676605.521, 9800581.813, 17229699.570, -114553918.527, 75676961.194],
    [4676612.913, 9800534.070, 17229700.223, -114553951.760, 75677002.767],
    [4676620.307, 9800486.325, 17229700.876, -114553984.993, 75677044.341],
    [4676627.700, 9800438.581, 17229701.529, -114554018.226, 75677085.915],
    [4676635.093, 9800390.836, 17229702.183, -114554051.459, 75677127.489],
    [-20586699.059, 19124701.927, 33333657.817, -144000817.673, 85019993.203],
    [-37698513.382, 30847699.939, 52368228.692, -159552447.086, 92989162.663],
    [-43888725.647, 35779657.106, 60960976.370, -164301181.841, 95785835.780],
    [-43888717.102, 35779623.022, 60960969.634, -164301194.729, 95785857.934],
]


def _ball_by_supports(Q):
    """The smallest ball through any support of at most d + 1 points of Q that holds
    them all (brute force over the supports: an independent check)."""
    import itertools
    k, d = Q.shape
    best = math.inf
    for size in range(2, d + 2):
        for sup in itertools.combinations(range(k), size):
            e = Q[list(sup[1:])] - Q[sup[0]]
            A = 2 * e @ e.T
            if np.linalg.cond(A) > 1e12:
                continue
            centre = Q[sup[0]] + np.linalg.solve(A, (e ** 2).sum(1)) @ e
            best = min(best, math.sqrt(((Q - centre) ** 2).sum(1).max()))
    return best


def test_min_ball_of_a_dwelling_path():
    """A path with near-copies of its support points (above) once did not reach the
    default tolerance in 100 000 iterations (the pivoting started from the points near
    the largest distance, crowded by the copies); the ball now agrees with the brute
    force over supports to 1e-12 (measured 3e-16), at the default tolerance and at
    1e-12."""
    P = np.array(DWELLING_PATH)[None]
    exact = _ball_by_supports(P[0] - P[0].mean(0))
    for tol in (1e-9, 1e-12):
        c, r = min_ball(P, tolerance=tol)
        assert r[0] == pytest.approx(exact, rel=1e-12)
        assert np.sqrt(((P[0] - c[0]) ** 2).sum(1)).max() <= r[0] * (1 + 1e-12)


def test_deviatoric_coordinates_norm_is_sqrt_j2():
    rng = np.random.default_rng(2)
    s = rng.normal(size=(50, 6))
    u = deviatoric_coordinates(s)
    mean = s[:, :3].sum(1) / 3
    d = s.copy()
    d[:, :3] -= mean[:, None]
    j2 = 0.5 * (d[:, :3] ** 2).sum(1) + (d[:, 3:] ** 2).sum(1)
    assert np.allclose((u ** 2).sum(1), j2, rtol=1e-13)


def test_plane_normals_cover_the_hemisphere_once():
    n, th, ph = plane_normals(10.0)
    assert np.allclose((n ** 2).sum(1), 1.0) and np.all(n[:, 2] >= -1e-15)
    dots = np.abs(n @ n.T) - np.eye(len(n))
    assert dots.max() < 1 - 1e-6            # no plane twice (n and -n are one plane)


# --------------------------------------------------------------------------- errors

@pytest.mark.parametrize("criterion, kwargs, match", [
    ("miner", {}, r"criterion = 'miner': allowed 'amplitude', 'crossland', 'dang_van', 'swt'"),
    ("crossland", {"torsion_limit": 3e8}, r"missing bending_limit \[Pa\]"),
    ("dang_van", {**LIMITS, "young": 2e11}, r"unknown constant\(s\) young"),
    ("swt", {}, r"missing young \[Pa\]"),
    ("crossland", {"torsion_limit": -1.0, "bending_limit": 4e8}, r"must be > 0"),
    ("crossland", {**LIMITS, "shear_amplitude": "max"}, r"shear_amplitude = 'max'"),
    # ~4e12 planes: refused before plane_normals is built (it exhausted the memory)
    ("swt", {"young": 2e11, "plane_step": 1e-4},
     r"plane_step = 0.0001 degrees: allowed 1 to 90 \(the smallest, 1, already holds "
     r"about 20600 planes"),
    ("swt", {"young": 2e11, "plane_step": 0.0}, r"plane_step = 0.0 degrees: allowed 1 to 90"),
])
def test_bad_constants(criterion, kwargs, match):
    with pytest.raises(ValueError, match=match):
        cp.fatigue(field(history(s11=1e8 * np.sin(T))), criterion, **kwargs)


def test_the_smallest_plane_step_counts_its_planes():
    """The refusal's plane count is the grid's: 20 629 normals at 1 degree (within 0.2 %
    of the 20 600 said), 206 at the default 10."""
    from contactpipe.post.fatigue import MIN_PLANE_STEP, plane_normals
    assert MIN_PLANE_STEP == 1.0
    assert len(plane_normals(1.0)[0]) == 20629
    assert len(plane_normals(10.0)[0]) == 206


def test_one_instant_is_not_a_cycle():
    one = field(history(s11=1e8 * np.sin(T))).isel(time=[3])
    with pytest.raises(ValueError, match=r"holds 1 instant: a fatigue criterion needs the "
                                         r"stress over a cycle"):
        cp.fatigue(one, "crossland", **LIMITS)


def test_every_criterion_is_tabulated():
    assert set(CRITERIA) == {"amplitude", "crossland", "dang_van", "swt"}
