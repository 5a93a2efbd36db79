"""Scene: construction, round trips, digest, replace, load program, auto grid."""
import copy
import math
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from contactpipe import materials
from contactpipe._util.files import loads_toml
from contactpipe.exceptions import SceneError
from contactpipe.scene import (
    BodySpec,
    Fretting,
    Friction,
    Geometry,
    Grid,
    Load,
    Output,
    Scene,
    Solver,
    TimeMesh,
)
from contactpipe.scene.parts import knot_steps
from contactpipe.testing import TINY_SCENES

REPO = Path(__file__).resolve().parents[1]

# The shared examples (../shared/examples), as contactpipe.testing carries them.
TINY_CREEP = TINY_SCENES["creep"]

TINY_FRETTING = TINY_SCENES["fretting"]

EXAMPLES = {"tiny-creep": TINY_CREEP, "tiny-fretting": TINY_FRETTING}


def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def fretting_dict():
    return loads_toml(TINY_FRETTING)


def assert_plain(obj, where="scene"):
    """Only TOML/JSON types: dict, list, str, int, float, bool."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            assert isinstance(k, str), where
            assert_plain(v, f"{where}.{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            assert_plain(v, f"{where}[{i}]")
    else:
        assert type(obj) in (str, int, float, bool), f"{where}: {type(obj).__name__}"


# ----------------------------------------------------------------------------- round trips

@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_toml_round_trip(tmp_path, name):
    s = Scene.from_toml(write(tmp_path, EXAMPLES[name]))
    assert s.name == name
    text = s.to_toml()
    assert Scene.from_toml_text(text) == s
    assert Scene.from_toml(write(tmp_path, text, "again.toml")) == s
    assert loads_toml(text) == s.to_dict()


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_dict_round_trip(name):
    s = Scene.from_dict(loads_toml(EXAMPLES[name]))
    d = s.to_dict()
    assert_plain(d)
    assert Scene.from_dict(d) == s
    assert Scene(**d) == s
    assert hash(Scene(**d)) == hash(s)


def test_to_dict_is_complete_with_defaults_resolved():
    d = Scene.from_dict(loads_toml(TINY_CREEP)).to_dict()
    assert d["solver"] == {"tolerance": 1e-9, "max_iterations": 2000, "time_rule": "auto",
                           "tangential": "auto", "max_coupling_passes": 100,
                           "preload_substeps": 8, "fft": "auto", "threads": 1}
    assert d["output"] == {"stride": 1, "precision": "float64", "compress": True}
    assert d["load"]["preload"] == "frictional"
    assert d["halfspace"]["young"] == 105e9 and isinstance(d["halfspace"]["young"], float)
    raw = loads_toml(TINY_CREEP)
    del raw["time"], raw["friction"]
    d2 = Scene.from_dict(raw).to_dict()
    assert d2["time"] == {"steps": 1}  # one step per knot interval
    assert d2["friction"] == {"mu": 0.0}


def test_parts_may_be_given_as_objects_or_dicts():
    d = fretting_dict()
    s = Scene(name="tiny-fretting", geometry=Geometry("sphere", radius=0.018),
              indenter=BodySpec("rigid"),
              halfspace=BodySpec("viscoelastic", young=105e9, poisson=0.3, creep="maxwell",
                                 relaxation_time=1.0),
              friction=Friction(0.1),
              load=Load(time=[0.0, 0.2, 0.6, 1.0], normal_force=1000,
                        tangential_force=[0, 90, -90, 90]),
              grid=Grid(points=[24, 24], size=[2e-3, 2e-3]), time=TimeMesh(20),
              solver=Solver(), output=Output())
    assert s == Scene.from_dict(d)
    assert s.load.time == (0.0, 0.2, 0.6, 1.0) and s.grid.points == (24, 24)


def test_scene_is_frozen_and_picklable():
    s = Scene.from_dict(fretting_dict())
    with pytest.raises(AttributeError):
        s.name = "x"
    with pytest.raises(AttributeError):
        s.friction.mu = 0.3
    assert pickle.loads(pickle.dumps(s)) == s
    assert copy.deepcopy(s) == s


def test_relative_surface_file_resolves_against_the_scene_folder(tmp_path):
    sub = tmp_path / "scenes"
    sub.mkdir()
    np.save(sub / "gap.npy", np.zeros((24, 24)))
    text = TINY_FRETTING.replace('shape = "sphere"\nradius = 0.018',
                                 'shape = "surface"\nfile = "gap.npy"')
    s = Scene.from_toml(write(sub, text))
    assert s.geometry.file == str(sub / "gap.npy")
    assert Scene.from_toml_text(s.to_toml()) == s
    x1, x2 = s.grid.coordinates()
    assert s.geometry.gap(x1, x2).shape == (24, 24)


# ----------------------------------------------------------------------------- digest

def test_digest_is_insensitive_to_key_order():
    d = fretting_dict()

    def reverse(obj):
        return {k: reverse(v) for k, v in reversed(list(obj.items()))} \
            if isinstance(obj, dict) else obj

    a, b = Scene.from_dict(d), Scene.from_dict(reverse(d))
    assert a.digest() == b.digest()
    assert len(a.digest()) == 16 and int(a.digest(), 16) >= 0


def test_digest_counts_physics_not_output():
    s = Scene.from_dict(fretting_dict())
    assert s.replace({"output.stride": 2, "output.precision": "float32"}).digest() == s.digest()
    assert s.replace({"friction.mu": 0.2}).digest() != s.digest()
    assert s.replace({"time.steps": 21}).digest() != s.digest()
    # a default left out or written out is the same scene
    d = fretting_dict()
    d["solver"] = {"tolerance": 1e-9}
    assert Scene.from_dict(d).digest() == s.digest()


def test_digest_is_stable_across_processes():
    code = ("import sys; from contactpipe._util.files import loads_toml; "
            "from contactpipe.scene import Scene; "
            "print(Scene.from_dict(loads_toml(sys.stdin.read())).digest())")
    out = subprocess.run([sys.executable, "-c", code], input=TINY_FRETTING, text=True,
                         capture_output=True, cwd=REPO, check=True,
                         env={"PYTHONHASHSEED": "123", "PATH": ""})
    assert out.stdout.strip() == Scene.from_dict(fretting_dict()).digest()


def test_digest_of_a_surface_follows_the_content(tmp_path):
    np.save(tmp_path / "a.npy", np.zeros((24, 24)))
    np.save(tmp_path / "b.npy", np.zeros((24, 24)))
    np.save(tmp_path / "c.npy", np.ones((24, 24)))
    d = fretting_dict()
    d["geometry"] = {"shape": "surface", "file": str(tmp_path / "a.npy")}
    a = Scene.from_dict(d)
    assert a.replace({"geometry.file": str(tmp_path / "b.npy")}).digest() == a.digest()
    assert a.replace({"geometry.file": str(tmp_path / "c.npy")}).digest() != a.digest()


# ----------------------------------------------------------------------------- replace

def test_replace_with_dotted_paths():
    s = Scene.from_dict(fretting_dict())
    s2 = s.replace({"friction.mu": 0.2, "halfspace.relaxation_time": 0.5, "name": "b"})
    assert (s2.friction.mu, s2.halfspace.relaxation_time, s2.name) == (0.2, 0.5, "b")
    assert s.friction.mu == 0.1  # the original is untouched
    assert s2.load == s.load and s2.grid == s.grid


def test_replace_revalidates():
    s = Scene.from_dict(fretting_dict())
    with pytest.raises(SceneError, match=r"friction\.mu must be a finite number >= 0, got -1"):
        s.replace({"friction.mu": -1})
    with pytest.raises(SceneError, match=r"load\.tangential_force reaches 90 N .* above "
                                         r"friction\.mu \* W = 50 N"):
        s.replace({"friction.mu": 0.05})
    with pytest.raises(SceneError, match=r"unknown key 'friction\.nu'"):
        s.replace({"friction.nu": 0.1})
    with pytest.raises(SceneError, match=r"cannot set 'friction\.mu\.x': friction\.mu is 0\.1"):
        s.replace({"friction.mu.x": 1})


def test_replace_into_the_fretting_preset_and_back():
    s = Scene.from_dict(fretting_dict())
    f = s.replace({"load.time": None, "load.tangential_force": None,
                   "load.fretting": {"amplitude": 90.0, "window": 1.0}})
    assert f.load.fretting == Fretting(amplitude=90.0, window=1.0)
    f2 = f.replace({"load.fretting.window": 2.0, "load.fretting.cycles": 2})
    t, W, T1, T2 = f2.load.knots()
    assert t[-1] == 2.0 and len(t) == 6
    assert f2.time.steps == 20  # given explicitly in the base scene: kept
    # a derived default (the least mesh holding every knot: 0, 0.2, 0.6, 1 -> 5 steps)
    # is derived again
    g = Scene.from_dict({k: v for k, v in fretting_dict().items() if k != "time"})
    assert g.time.steps == 5
    g2 = g.replace({"load.time": [0.0, 1.0], "load.tangential_force": [0.0, 50.0]})
    assert g2.time.steps == 1
    g3 = g.replace({"load.time": [0.0, 1.0, 2.0, 3.0]})
    assert g3.time.steps == 3  # equally spaced knots: one step per interval


# ----------------------------------------------------------------------------- load program

def test_instants_of_tiny_creep():
    s = Scene.from_dict(loads_toml(TINY_CREEP))
    t, W, T1, T2 = s.instants()
    np.testing.assert_allclose(t, np.linspace(0.0, 1.0, 11))
    assert t[0] == 0.0 and t[-1] == 1.0
    assert np.all(W == 1000.0)  # a step at time[0]: W = 1000 N at every instant, t0 too
    assert np.all(T1 == 0.0) and np.all(T2 == 0.0)
    assert s.load.step_load and s.load.window == 1.0


def test_instants_of_tiny_fretting():
    s = Scene.from_dict(fretting_dict())
    t, W, T1, T2 = s.instants()
    assert len(t) == 21
    np.testing.assert_allclose(t, np.arange(21) * 0.05, atol=1e-15)
    assert np.all(W == 1000.0)
    # 0 -> 90 over [0, 0.2], 90 -> -90 over [0.2, 0.6], -90 -> 90 over [0.6, 1]
    expected = np.interp(t, [0.0, 0.2, 0.6, 1.0], [0.0, 90.0, -90.0, 90.0])
    np.testing.assert_allclose(T1, expected, atol=1e-12)
    np.testing.assert_allclose(T1[[0, 2, 4, 8, 12, 16, 20]], [0, 45, 90, 0, -90, 0, 90],
                               atol=1e-12)
    assert np.all(T2 == 0.0)
    t5, *_ = s.load.instants(5)
    np.testing.assert_allclose(t5, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0])


def test_normal_force_list_and_tangential_pairs():
    d = fretting_dict()
    d["load"] = {"time": [1.0, 2.0, 3.0], "normal_force": [0.0, 1000.0, 500.0],
                 "tangential_force": [[0.0, 0.0], [30.0, 40.0], [0.0, -20.0]]}
    s = Scene.from_dict(d)
    assert not s.load.step_load and s.time.steps == 20
    t, W, T1, T2 = s.load.knots()
    assert list(W) == [0, 1000, 500] and list(T1) == [0, 30, 0] and list(T2) == [0, 40, -20]
    t, W, T1, T2 = s.load.instants(4)
    np.testing.assert_allclose(t, [1.0, 1.5, 2.0, 2.5, 3.0])
    np.testing.assert_allclose(W, [0, 500, 1000, 750, 500])
    np.testing.assert_allclose(T2, [0, 20, 40, 10, -20])


def test_fretting_preset_equals_the_explicit_knots():
    explicit = Scene.from_dict(fretting_dict())
    d = fretting_dict()
    del d["load"]["time"], d["load"]["tangential_force"]
    d["load"]["fretting"] = {"amplitude": 90.0, "window": 1.0}
    preset = Scene.from_dict(d)
    for a, b in zip(preset.load.knots(), explicit.load.knots(), strict=True):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(preset.instants(), explicit.instants(), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    assert preset.load.fretting.cycles == 1 and preset.load.window == 1.0
    assert Scene.from_toml_text(preset.to_toml()) == preset
    assert "[load.fretting]" in preset.to_toml()


def test_fretting_preset_cycles_and_direction():
    f = Fretting(amplitude=10.0, window=9.0, cycles=2, direction=90.0)
    t, T = f.knots()
    np.testing.assert_allclose(t, [0, 1, 3, 5, 7, 9])  # 1 + 4 n = 9 units
    np.testing.assert_array_equal(T, [0, 10, -10, 10, -10, 10])
    load = Load(normal_force=500.0, fretting=f)
    _, W, T1, T2 = load.knots()
    assert np.all(T1 == 0.0) and np.array_equal(T2, T) and np.all(W == 500.0)
    _, _, T1, T2 = Load(normal_force=500.0, fretting=Fretting(10.0, 9.0, direction=30)).knots()
    np.testing.assert_allclose(np.hypot(T1, T2), [0, 10, 10, 10])
    np.testing.assert_allclose(T2[1] / T1[1], math.tan(math.radians(30)))


def test_single_knot_load_has_one_instant():
    d = loads_toml(TINY_CREEP)
    d["load"]["time"] = [0.0]
    del d["time"]
    s = Scene.from_dict(d)
    assert s.time.steps == 0 and s.load.window == 0.0
    t, W, T1, T2 = s.instants()
    assert list(t) == [0.0] and list(W) == [1000.0]
    assert Scene.from_dict(s.to_dict()) == s
    d["time"] = {"steps": 5}
    with pytest.raises(SceneError, match=r"time\.steps = 5 needs a load program with a "
                                         r"duration"):
        Scene.from_dict(d)


def _preset(cycles=1, window=1.0, amplitude=90.0):
    d = fretting_dict()
    del d["time"], d["load"]["time"], d["load"]["tangential_force"]
    d["grid"]["size"] = "auto"        # a long window creeps beyond the tiny grid
    d["load"]["fretting"] = {"amplitude": amplitude, "window": window, "cycles": cycles}
    return Scene.from_dict(d)


def test_fretting_preset_without_time_holds_every_knot():
    """The default mesh is the least that holds every knot: 0, 1/5, 3/5, 1 of the window
    -> 5 steps, so T1 runs 0, 90, -90, 90 N at the knots (3 steps cut the loop to
    0, 30, -60, 90 N)."""
    s = _preset()
    assert s.time.steps == 5 and s.to_dict()["time"] == {"steps": 5}
    t, W, T1, T2 = s.instants()
    np.testing.assert_allclose(t, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0], atol=1e-15)
    np.testing.assert_allclose(T1, [0.0, 90.0, 0.0, -90.0, 0.0, 90.0], atol=1e-12)
    two = _preset(cycles=2, window=9.0, amplitude=10.0)
    assert two.time.steps == 9  # 1 + 4 n
    t, _, T1, _ = two.instants()
    np.testing.assert_allclose(T1[[0, 1, 3, 5, 7, 9]], [0, 10, -10, 10, -10, 10], atol=1e-12)
    assert _preset(cycles=100_000).time.steps == 400_001
    assert Scene.from_toml_text(s.to_toml()) == s


def test_the_archive_of_a_preset_reaches_every_knot():
    """End to end: the default mesh of the preset puts the turning points in the archive
    (24 x 24 grid, 5 steps; T1 reached to 1e-9 of T*)."""
    import contactpipe as cp
    ds = cp.simulate(_preset())
    np.testing.assert_allclose(ds["time"].values, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0], atol=1e-15)
    np.testing.assert_allclose(ds["T1"].values, [0.0, 90.0, 0.0, -90.0, 0.0, 90.0],
                               atol=90.0 * 1e-9)


def test_knot_steps():
    assert knot_steps([0.0]) == 0 and knot_steps([2.0, 3.0]) == 1
    assert knot_steps([0.0, 0.2, 0.6, 1.0]) == 5
    assert knot_steps([0.0, 1 / 3, 1.0]) == 3 and knot_steps([1.0, 1.25, 1.5, 2.0]) == 4
    assert knot_steps([0.0, 0.1, 0.35, 1.7]) == 34       # 1/17, 7/34
    assert knot_steps([0.0, 1 / math.pi, 1.0]) is None   # on no mesh of <= 1e6 steps
    assert knot_steps([0.0, 0.5, 1.0], limit=1) is None
    assert knot_steps([0.0, 1e-6, 1.0]) == 1_000_000 and knot_steps([0.0, 1e-7, 1.0]) is None


@settings(max_examples=200, deadline=None)
@given(st.floats(-1e3, 1e3, allow_nan=False), st.floats(1e-4, 1e3, allow_nan=False),
       st.lists(st.integers(1, 60), min_size=1, max_size=6))
def test_knot_steps_of_commensurate_knots(t0, unit, gaps):
    """Knots t0 + n_k u: the least mesh has N / gcd(N, n_1, ..., n_K) steps (N = n_last),
    whatever the float rounding of the times."""
    n = np.cumsum(gaps)
    t = [t0] + [t0 + float(k) * unit for k in n]
    expected = int(n[-1]) // math.gcd(int(n[-1]), *(int(k) for k in n))
    assert knot_steps(t) == expected


def test_hertz_semi_axes_is_the_hertz_contact_radius():
    """Elastic sphere: a = (3 W R / (4 E*))^(1/3) of analytic.hertz_sphere (rel 1e-12);
    the window's largest creep factor for a Maxwell body (phi = 2 at t = t'), phi(0) = 1
    with moduli="instantaneous"."""
    from contactpipe import analytic
    s = Scene.from_dict(loads_toml(TINY_CREEP))
    e_star = 105e9 / (1 - 0.3**2)
    glassy = analytic.hertz_sphere(1000.0, 0.018, e_star).contact_radius
    relaxed = analytic.hertz_sphere(1000.0, 0.018, e_star / 2).contact_radius
    assert s.hertz_semi_axes("instantaneous") == pytest.approx((glassy, glassy), rel=1e-12)
    assert s.hertz_semi_axes() == pytest.approx((relaxed, relaxed), rel=1e-12)
    punch = s.replace({"geometry": {"shape": "flat_punch", "radius": 1e-3}})
    assert punch.hertz_semi_axes() == (1e-3, 1e-3)
    with pytest.raises(ValueError, match="moduli"):
        s.hertz_semi_axes("glassy")


EXTREMES = [5e-324, 1e-300, 1e-30, 1e-3, 1.0, 1e30, 1e300, 1.7976931348623157e308]


@st.composite
def extreme_scenes(draw):
    x = st.sampled_from(EXTREMES)
    d = loads_toml(TINY_CREEP)
    shape = draw(st.sampled_from(["sphere", "ellipsoid", "flat_punch"]))
    d["geometry"] = ({"shape": shape, "radii": [draw(x), draw(x)]} if shape == "ellipsoid"
                     else {"shape": shape, "radius": draw(x)})
    creep = draw(st.sampled_from(["maxwell", "kelvin_voigt", "zener", "prony", "tabulated"]))
    young = draw(x)
    body = {"material": "viscoelastic", "young": young, "poisson": draw(st.sampled_from(
        [0.0, 0.3, 0.5])), "creep": creep}
    if creep == "maxwell":
        body["relaxation_time"] = draw(x)
    elif creep in ("kelvin_voigt", "zener"):
        body["retardation_time"] = draw(x)
        if creep == "zener":
            body["relaxed_young"] = young * draw(st.sampled_from([1e-300, 1e-3, 0.5]))
    elif creep == "prony":
        body["terms"] = [[draw(x), draw(x)]]
        body["relaxation_time"] = draw(x)
    else:
        body["table"] = [[0.0, draw(x)], [draw(x), 1.7976931348623157e308]]
    d[draw(st.sampled_from(["indenter", "halfspace"]))] = body
    d["load"] = {"time": [0.0, draw(x)], "normal_force": draw(x)}
    d["grid"]["size"] = draw(st.sampled_from(["auto", [draw(x), draw(x)]]))
    if draw(st.booleans()):
        d["solver"] = {"accuracy": draw(st.sampled_from(["fast", "accurate"]))}
    return d


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(extreme_scenes())
def test_extreme_constants_never_warn(d):
    """Validation and the scene's derived quantities with constants from 5e-324 to 1.8e308:
    a scene or one SceneError, never a warning (numpy's RuntimeWarnings included) nor
    another exception."""
    import warnings

    from contactpipe.planning.accuracy import resolve_accuracy
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            s = Scene.from_dict(d)
        except SceneError as err:
            assert all("\n" not in p for p in err.problems)
            return
        s.resolved_grid_size()
        s.hertz_semi_axes()
        s.hertz_semi_axes("instantaneous")
        s.instants()
        assert Scene.from_toml_text(s.to_toml()) == s
        try:
            resolve_accuracy(s)
        except SceneError:
            pass


# ----------------------------------------------------------------------------- bodies

@pytest.mark.parametrize("spec, phi_at_1", [
    (dict(creep="maxwell", relaxation_time=2.0), 1.5),
    (dict(creep="kelvin_voigt", retardation_time=1.0), 1 - math.exp(-1)),
    (dict(creep="zener", relaxed_young=50e9, retardation_time=1.0),
     2 - math.exp(-1)),
    (dict(creep="prony", terms=[[0.5, 1.0]], relaxation_time=4.0),
     1 + 0.5 * (1 - math.exp(-1)) + 0.25),
    (dict(creep="tabulated", table=[[0.0, 1.0], [2.0, 3.0]]), 2.0),
])
def test_body_creep_functions(spec, phi_at_1):
    b = BodySpec("viscoelastic", young=100e9, poisson=0.3, **spec).body()
    assert isinstance(b, materials.Body) and b.kind == "viscoelastic"
    assert b.young == 100e9 and b.poisson == 0.3
    assert float(b.creep(1.0)) == pytest.approx(phi_at_1, rel=1e-12)


def test_rigid_and_elastic_bodies():
    assert BodySpec("rigid").body().rigid
    e = BodySpec("elastic", young=210e9, poisson=0.3).body()
    assert e.kind == "elastic" and not e.has_memory and e.young == 210e9


# ----------------------------------------------------------------------------- auto grid

def test_auto_grid_size_sphere_on_maxwell():
    s = Scene.from_dict(loads_toml(TINY_CREEP)).replace({"grid.size": "auto"})
    assert s.grid.size == "auto"
    E, nu, R, W, phi_max = 105e9, 0.3, 0.018, 1000.0, 2.0  # phi = 1 + t/t' up to t = 1 s
    e_star = E / (1 - nu**2)
    a = (3 * W * R * phi_max / (4 * e_star)) ** (1 / 3)
    L1, L2 = s.resolved_grid_size()
    assert L1 == pytest.approx(3 * a, rel=1e-12) and L2 == pytest.approx(3 * a, rel=1e-12)
    g = s.resolved_grid()
    assert g.size == (L1, L2) and g.points == (24, 24)
    x1, _ = g.coordinates()
    assert x1[-1] == pytest.approx(L1 / 2 - L1 / 48)
    assert Scene.from_toml_text(s.to_toml()) == s  # "auto" stays "auto"
    with pytest.raises(SceneError, match=r"grid\.size is 'auto'"):
        s.grid.coordinates()
    # a given size is the size used
    assert Scene.from_dict(loads_toml(TINY_CREEP)).resolved_grid_size() == (2.4e-3, 2.4e-3)


def test_auto_grid_size_two_compliant_bodies_and_other_shapes():
    s = Scene.from_dict(loads_toml(TINY_CREEP)).replace({
        "grid.size": "auto", "indenter": {"material": "elastic", "young": 210e9,
                                          "poisson": 0.25}})
    e_star = 1 / (2 * (1 - 0.3**2) / 105e9 + (1 - 0.25**2) / 210e9)
    a = (3 * 1000 * 0.018 / (4 * e_star)) ** (1 / 3)
    assert s.resolved_grid_size()[0] == pytest.approx(3 * a, rel=1e-12)
    punch = s.replace({"geometry": {"shape": "flat_punch", "radius": 1e-3}})
    assert punch.resolved_grid_size() == pytest.approx((2.5e-3, 2.5e-3))
    ell = s.replace({"geometry": {"shape": "ellipsoid", "radii": [0.04, 0.01]}})
    L1, L2 = ell.resolved_grid_size()
    assert L1 > L2 and L1 / L2 == pytest.approx(4 ** (2 / 3))
    assert L1 * L2 == pytest.approx((3 * (3 * 1000 * 0.02 / (4 * e_star)) ** (1 / 3)) ** 2)


# ----------------------------------------------------------------------------- properties

finite = dict(allow_nan=False, allow_infinity=False)


@st.composite
def body_dicts(draw, allow_rigid=True):
    material = draw(st.sampled_from(["rigid", "elastic", "viscoelastic"] if allow_rigid
                                    else ["elastic", "viscoelastic"]))
    if material == "rigid":
        return {"material": "rigid"}
    young = draw(st.floats(1e6, 1e12, **finite))
    d = {"material": material, "young": young, "poisson": draw(st.floats(0.0, 0.5, **finite))}
    if material == "elastic":
        return d
    creep = draw(st.sampled_from(["maxwell", "kelvin_voigt", "zener", "prony", "tabulated"]))
    d["creep"] = creep
    tau = st.floats(1e-4, 1e4, **finite)
    if creep == "maxwell":
        d["relaxation_time"] = draw(tau)
    elif creep == "kelvin_voigt":
        d["retardation_time"] = draw(tau)
    elif creep == "zener":
        d["relaxed_young"] = young * draw(st.floats(0.01, 0.99, **finite))
        d["retardation_time"] = draw(tau)
    elif creep == "prony":
        d["terms"] = draw(st.lists(st.tuples(st.floats(1e-3, 10, **finite), tau).map(list),
                                   min_size=1, max_size=3))
        if draw(st.booleans()):
            d["relaxation_time"] = draw(tau)
    else:
        dt = draw(st.lists(st.floats(1e-3, 10, **finite), min_size=1, max_size=4))
        dphi = draw(st.lists(st.floats(0, 2, **finite), min_size=len(dt), max_size=len(dt)))
        t = np.concatenate([[0.0], np.cumsum(dt)])
        phi0 = draw(st.sampled_from([0.0, 1.0]))
        phi = np.concatenate([[phi0], phi0 + 0.1 + np.cumsum(dphi)])
        d["table"] = [[float(a), float(b)] for a, b in zip(t, phi, strict=True)]
    return d


def _phi0_zero(body):
    return body.get("creep") == "kelvin_voigt" or (
        body.get("creep") == "tabulated" and body["table"][0][1] == 0.0)


@st.composite
def scene_dicts(draw):
    shape = draw(st.sampled_from(["sphere", "ellipsoid", "flat_punch"]))
    radius = st.floats(1e-5, 1.0, **finite)
    geometry = {"shape": shape}
    if shape == "ellipsoid":
        geometry["radii"] = [draw(radius), draw(radius)]
    else:
        geometry["radius"] = draw(radius)
        if shape == "flat_punch" and draw(st.booleans()):
            geometry["height"] = draw(radius)
    indenter = draw(body_dicts())
    halfspace = draw(body_dicts(allow_rigid=indenter["material"] != "rigid"))
    mu = draw(st.sampled_from([0.0, draw(st.floats(0.0, 2.0, **finite))]))
    load = {}
    force = st.floats(1e-3, 1e6, **finite)
    commensurate = True  # the knots lie on a uniform mesh (a fretting preset's do)
    W = draw(force)
    fraction = draw(st.floats(0.01, 0.9, **finite))
    # a fretting preset needs T* = fraction * mu * W > 0: a subnormal mu can round it to 0
    if W * mu * fraction > 0 and draw(st.booleans()):
        load["normal_force"] = W
        load["fretting"] = {"amplitude": W * mu * fraction,
                            "window": draw(st.floats(1e-3, 1e3, **finite)),
                            "cycles": draw(st.integers(1, 5)),
                            "direction": draw(st.floats(-360, 360, **finite))}
        n = 2 * load["fretting"]["cycles"] + 2
    else:
        n = draw(st.integers(1, 6))
        t0 = draw(st.floats(-10, 10, **finite))
        commensurate = draw(st.booleans())
        if not commensurate:  # any knots: time.steps is then given (below)
            dts = draw(st.lists(st.floats(1e-3, 10, **finite), min_size=n - 1,
                                max_size=n - 1))
        else:  # commensurate knots: the default mesh holds them all
            unit = draw(st.floats(1e-3, 10, **finite))
            dts = [k * unit for k in draw(st.lists(st.integers(1, 12), min_size=n - 1,
                                                   max_size=n - 1))]
        load["time"] = [t0] + [float(x) for x in t0 + np.cumsum(dts)]
        if draw(st.booleans()):
            W = [draw(force) for _ in range(n)]
            load["normal_force"] = W
        else:
            W = [draw(force)] * n
            load["normal_force"] = W[0]
        if mu > 0 and draw(st.booleans()):
            frac = [draw(st.floats(-0.9, 0.9, **finite)) for _ in range(n)]
            if draw(st.booleans()):
                load["tangential_force"] = [f * mu * w for f, w in zip(frac, W, strict=True)]
            else:
                ang = [draw(st.floats(0, 2 * math.pi, **finite)) for _ in range(n)]
                load["tangential_force"] = [[f * mu * w * math.cos(a), f * mu * w * math.sin(a)]
                                            for f, w, a in zip(frac, W, ang, strict=True)]
    if draw(st.booleans()):
        load["preload"] = draw(st.sampled_from(["frictional", "frictionless"]))
    window = (load["fretting"]["window"] if "fretting" in load
              else load["time"][-1] - load["time"][0])
    for body in (indenter, halfspace):  # a creep table must reach the end of the window
        if body.get("creep") == "tabulated" and body["table"][-1][0] < window:
            body["table"].append([window, body["table"][-1][1]])
    no_instant = _phi0_zero(indenter) or _phi0_zero(halfspace)
    grid = {"points": [draw(st.integers(8, 64)), draw(st.integers(8, 64))]}
    grid["size"] = ("auto" if not no_instant and draw(st.booleans())
                    else [draw(st.floats(1e-6, 1.0, **finite)) for _ in range(2)])
    if grid["size"] != "auto":      # a random size seldom holds the contact: not checked
        grid["size_check"] = False
    d = {"geometry": geometry, "indenter": indenter, "halfspace": halfspace, "load": load,
         "grid": grid}
    if draw(st.booleans()):
        d["name"] = draw(st.text(min_size=1, max_size=12))
    if mu > 0 or draw(st.booleans()):
        d["friction"] = {"mu": mu}
    if n > 1 and (not commensurate or draw(st.booleans())):
        d["time"] = {"steps": draw(st.integers(1, 500))}
    if draw(st.booleans()):
        d["solver"] = {
            "tolerance": draw(st.floats(1e-14, 1e-2, **finite)),
            "max_iterations": draw(st.integers(1, 10**6)),
            # step_start is valid only below its stability bound: tested in test_errors
            "time_rule": draw(st.sampled_from(["auto", "bdf2", "linear"])),
            "tangential": draw(st.sampled_from(["auto", "scalar", "vector"])),
            "fft": draw(st.sampled_from(["auto", "pyfftw", "scipy"])),
            "threads": draw(st.integers(1, 64)),
        }
        if draw(st.booleans()):
            d["solver"]["accuracy"] = draw(st.sampled_from(["fast", "balanced", "accurate"]))
    if draw(st.booleans()):
        d["output"] = {"stride": draw(st.integers(1, 100)),
                       "precision": draw(st.sampled_from(["float64", "float32"])),
                       "compress": draw(st.booleans())}
    return d


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene_dicts())
def test_random_valid_scenes_round_trip(d):
    s = Scene.from_dict(d)
    out = s.to_dict()
    assert_plain(out)
    assert Scene.from_dict(out) == s
    assert Scene.from_toml_text(s.to_toml()) == s
    assert Scene.from_dict(copy.deepcopy(out)).digest() == s.digest()
    t, W, T1, T2 = s.instants()
    assert len(t) == s.time.steps + 1 and np.all(np.isfinite(W))
    if "time" not in d:  # the default mesh holds every knot
        knots = s.load.knots()[0]
        span = max(knots[-1] - knots[0], 1e-300)
        assert all(np.min(np.abs(t - tk)) <= 1e-9 * span + 1e-12 * abs(tk) for tk in knots)
    if s.grid.size == "auto":
        assert all(L > 0 and math.isfinite(L) for L in s.resolved_grid_size())


def _set(d, path, value):
    node = d
    *head, last = path.split(".")
    for k in head:
        node = node.setdefault(k, {})
    node[last] = value


not_a_number = st.one_of(st.text(max_size=5), st.booleans(), st.just(float("nan")),
                         st.just(float("inf")), st.just(-float("inf")),
                         st.lists(st.integers(), max_size=2), st.just({}))
negative = st.floats(max_value=0.0, allow_nan=False, allow_infinity=False)

#: (dotted path, values that are always wrong there) on the tiny-fretting scene.
INVALID = [
    ("geometry.shape", st.text(max_size=8).filter(
        lambda s: s not in ("sphere", "ellipsoid", "flat_punch", "surface"))),
    ("geometry.radius", st.one_of(negative, not_a_number)),
    ("geometry.radii", st.lists(st.floats(1e-3, 1), max_size=3)),
    ("indenter.young", st.floats(1, 1e12)),
    ("halfspace.young", st.one_of(negative, not_a_number)),
    ("halfspace.poisson", st.one_of(st.floats(0.5, 1e3, exclude_min=True),
                                    st.floats(-1e3, 0, exclude_max=True), not_a_number)),
    ("halfspace.creep", st.text(max_size=8)),
    ("halfspace.relaxation_time", st.one_of(negative, not_a_number)),
    ("halfspace.retardation_time", st.floats(1e-3, 10)),
    ("friction.mu", st.one_of(st.floats(max_value=0.0899, allow_nan=False), not_a_number)),
    ("load.normal_force", st.one_of(st.floats(-1e6, 899.0), not_a_number)),
    ("load.time", st.lists(st.floats(-1, 1, allow_nan=False), min_size=4, max_size=4).filter(
        lambda t: any(b <= a for a, b in zip(t, t[1:], strict=False)))),
    ("load.tangential_force", st.lists(st.floats(-80, 80), min_size=0, max_size=3)),
    ("load.preload", st.text(max_size=8)),
    ("grid.points", st.one_of(st.lists(st.integers(-10, 7), min_size=2, max_size=2),
                              st.lists(st.integers(4097, 10**9), min_size=2, max_size=2),
                              st.lists(st.integers(8, 64), min_size=3, max_size=4),
                              st.lists(st.floats(8.5, 60.5), min_size=2, max_size=2))),
    ("grid.size", st.one_of(st.lists(negative, min_size=2, max_size=2),
                            st.text(max_size=5).filter(lambda s: s != "auto"), st.booleans(),
                            st.just([float("nan"), 1e-3]),
                            st.lists(st.floats(1e-3, 1.0), min_size=3, max_size=4))),
    ("time.steps", st.one_of(st.integers(max_value=0), not_a_number)),
    ("solver.tolerance", st.one_of(st.floats(min_value=0.0101), negative, not_a_number)),
    ("solver.max_iterations", st.one_of(st.integers(max_value=0), st.floats(1.5, 10))),
    ("solver.time_rule", st.text(max_size=8)),
    ("output.stride", st.integers(max_value=0)),
    ("output.compress", st.one_of(st.integers(), st.text(max_size=3))),
    ("surplus_key", st.integers()),
]


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_random_invalid_values_raise_scene_error(data):
    path, values = data.draw(st.sampled_from(INVALID))
    value = data.draw(values)
    d = fretting_dict()
    _set(d, path, value)
    with pytest.raises(SceneError, match=path.split(".")[-1] if path != "surplus_key"
                       else "unknown key 'surplus_key'"):
        Scene.from_dict(d)


junk = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-10**400, 10**400), st.floats(),
              st.text(max_size=6)),
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=8)
PATHS = [p for p, _ in INVALID] + [
    "geometry", "indenter", "load", "load.fretting", "load.fretting.cycles",
    "load.fretting.window", "halfspace.terms", "halfspace.table", "halfspace.relaxed_young",
    "grid", "time", "solver", "output", "name", "solver.accuracy", "geometry.file",
    "halfspace.material", "output.precision", "solver.threads"]


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(PATHS), junk)
def test_any_value_anywhere_gives_a_scene_or_a_scene_error(path, value):
    d = fretting_dict()
    _set(d, path, value)
    try:
        s = Scene.from_dict(d)
    except SceneError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
    else:
        assert Scene.from_dict(s.to_dict()) == s
