"""Every scene mistake raises SceneError naming the field, the value and what is allowed."""
import re

import numpy as np
import pytest

from contactpipe.exceptions import SceneError
from contactpipe.scene import BodySpec, Friction, Geometry, Grid, Load, Scene

DELETE = object()


def base():
    """tiny-fretting (../shared/examples) as a dict."""
    return {
        "name": "tiny-fretting",
        "geometry": {"shape": "sphere", "radius": 0.018},
        "indenter": {"material": "rigid"},
        "halfspace": {"material": "viscoelastic", "young": 105e9, "poisson": 0.3,
                      "creep": "maxwell", "relaxation_time": 1.0},
        "friction": {"mu": 0.1},
        "load": {"time": [0.0, 0.2, 0.6, 1.0], "normal_force": 1000.0,
                 "tangential_force": [0.0, 90.0, -90.0, 90.0]},
        "grid": {"points": [24, 24], "size": [2.0e-3, 2.0e-3]},
        "time": {"steps": 20},
    }


def scene_with(changes):
    """The base scene with dotted-path changes (DELETE removes a key)."""
    d = base()
    for path, value in changes.items():
        node = d
        *head, last = path.split(".")
        for k in head:
            node = node.setdefault(k, {})
        if value is DELETE:
            node.pop(last, None)
        else:
            node[last] = value
    return Scene.from_dict(d)


VE = {"material": "viscoelastic", "young": 100e9, "poisson": 0.3}
FRETTING = {"load.time": DELETE, "load.tangential_force": DELETE,
            "load.fretting": {"amplitude": 90.0, "window": 1.0}}

# (id, changes to the base scene, regex the message must match)
MISTAKES = [
    # structure
    ("unknown top-level key", {"nmae": "x"},
     r"unknown key 'nmae' \(did you mean 'name'\?\) at the top level of the scene; "
     r"allowed keys: name, geometry"),
    ("unknown nested key", {"geometry.radiu": 0.01},
     r"unknown key 'geometry\.radiu' \(did you mean 'radius'\?\); allowed keys in "
     r"\[geometry\]: shape, radius, radii, file, height"),
    ("unknown key in fretting", {**FRETTING, "load.fretting.period": 1.0},
     r"unknown key 'load\.fretting\.period'; allowed keys in \[load\.fretting\]: amplitude"),
    ("section not a table", {"friction": 0.1},
     r"friction must be a table \(dict\) with mu, got 0\.1"),
    ("missing section", {"halfspace": DELETE},
     r"halfspace is required: a table \[halfspace\] with material = rigid"),
    ("missing geometry.shape", {"geometry.shape": DELETE},
     r"geometry\.shape is required: one of 'sphere', 'ellipsoid', 'flat_punch', 'surface'"),
    ("missing load.normal_force", {"load.normal_force": DELETE},
     r"load\.normal_force is required: a force >= 0 \[N\]"),
    ("missing load.time", {"load.time": DELETE},
     r"load\.time is required \(or a \[load\.fretting\] preset\)"),
    ("missing grid.points", {"grid.points": DELETE},
     r"grid\.points is required: two integers \[N1, N2\], each from 8 to 4096"),
    ("missing grid.size", {"grid.size": DELETE}, r"grid\.size is required: .* or 'auto'"),
    # types
    ("string for a number", {"geometry.radius": "0.018"},
     r"geometry\.radius must be a finite number > 0 \[m\], got '0\.018' \(a string\)"),
    ("bool for a number", {"friction.mu": True},
     r"friction\.mu must be a finite number >= 0, got True \(a boolean\)"),
    ("NaN", {"halfspace.young": float("nan")},
     r"halfspace\.young must be a finite number > 0 \[Pa\], got nan"),
    ("inf", {"geometry.radius": float("inf")}, r"geometry\.radius must be .*, got inf"),
    ("NaN in a list", {"load.time": [0.0, float("nan"), 0.6, 1.0]},
     r"load\.time must be a list of at least 1 strictly increasing times \[s\], got "
     r"\[0\.0, nan"),
    ("name not a string", {"name": 3}, r"name must be a non-empty string, got 3"),
    # choices
    ("unknown shape", {"geometry.shape": "cone"},
     r"geometry\.shape must be one of 'sphere', 'ellipsoid', 'flat_punch', 'surface', "
     r"'rough', "
     r"got 'cone'"),
    ("unknown material", {"halfspace.material": "plastic"},
     r"halfspace\.material must be one of 'rigid', 'elastic', 'viscoelastic', got 'plastic'"),
    ("unknown creep", {"halfspace.creep": "burgers"},
     r"halfspace\.creep must be one of 'maxwell', 'kelvin_voigt', 'zener', 'prony', "
     r"'tabulated', 'fit', got 'burgers'"),
    ("unknown preload", {"load.preload": "none"},
     r"load\.preload must be one of 'frictional', 'frictionless', got 'none'"),
    ("unknown time_rule", {"solver.time_rule": "trapezoid"},
     r"solver\.time_rule must be one of 'auto', 'bdf2', 'linear', 'step_start', got 'trapezoid'"),
    ("unknown tangential model", {"solver.tangential": "2d"},
     r"solver\.tangential must be one of 'auto', 'scalar', 'vector'"),
    ("unknown fft", {"solver.fft": "numpy"}, r"solver\.fft must be one of 'auto', 'pyfftw'"),
    ("unknown accuracy", {"solver.accuracy": "max"},
     r"solver\.accuracy must be one of 'fast', 'balanced', 'accurate', got 'max'"),
    ("unknown precision", {"output.precision": "float16"},
     r"output\.precision must be one of 'float64', 'float32', got 'float16'"),
    ("compress not a bool", {"output.compress": 1},
     r"output\.compress must be true or false, got 1"),
    # geometry
    ("radius <= 0", {"geometry.radius": 0.0},
     r"geometry\.radius must be a finite number > 0 \[m\], got 0\.0"),
    ("radius missing for sphere", {"geometry.radius": DELETE},
     r"geometry\.radius is required for shape = 'sphere'"),
    ("key of another shape", {"geometry.radii": [0.01, 0.02]},
     r"geometry\.radii = \[0\.01, 0\.02\] is not used by shape = 'sphere' \(it takes: "
     r"radius\); remove it"),
    ("ellipsoid radii not two", {"geometry": {"shape": "ellipsoid", "radii": [0.01]}},
     r"geometry\.radii must be two finite numbers > 0 \[m\], \[R1, R2\] along x1, x2, "
     r"got \[0\.01\]"),
    ("ellipsoid radii negative", {"geometry": {"shape": "ellipsoid", "radii": [0.01, -1]}},
     r"geometry\.radii must be two finite numbers > 0 .*got \[0\.01, -1\]"),
    ("punch height <= 0", {"geometry": {"shape": "flat_punch", "radius": 1e-3, "height": 0}},
     r"geometry\.height must be a finite number > 0 \[m\], got 0"),
    ("surface file missing", {"geometry": {"shape": "surface", "file": "/nonexistent/g.nc"}},
     r"geometry\.file '/nonexistent/g\.nc': no such file"),
    # bodies
    ("young <= 0", {"halfspace.young": -1e9},
     r"halfspace\.young must be a finite number > 0 \[Pa\], got -1000000000\.0"),
    ("poisson above 0.5", {"halfspace.poisson": 0.51},
     r"halfspace\.poisson must be a number in \[0, 0\.5\], got 0\.51"),
    ("poisson negative", {"halfspace.poisson": -0.1},
     r"halfspace\.poisson must be a number in \[0, 0\.5\], got -0\.1"),
    ("poisson missing", {"halfspace.poisson": DELETE},
     r"halfspace\.poisson is required for material = 'viscoelastic'"),
    ("creep keys on an elastic body", {"halfspace.material": "elastic"},
     r"halfspace\.creep = 'maxwell' is not used by an elastic body \(creep keys need "
     r"material = 'viscoelastic'\); remove it"),
    ("constants on a rigid body", {"indenter.young": 210e9, "indenter.poisson": 0.3},
     r"indenter\.young = 210000000000\.0 is not used by a rigid body \(material = 'rigid' "
     r"takes no constants\); remove it"),
    ("viscoelastic without creep", {"halfspace.creep": DELETE,
                                    "halfspace.relaxation_time": DELETE},
     r"halfspace\.creep is required for material = 'viscoelastic': one of 'maxwell'"),
    ("maxwell without relaxation_time", {"halfspace.relaxation_time": DELETE},
     r"halfspace\.relaxation_time is required for creep = 'maxwell'"),
    ("key of another creep model", {"halfspace.retardation_time": 1.0},
     r"halfspace\.retardation_time = 1\.0 is not used by creep = 'maxwell' \(it takes: "
     r"relaxation_time\)"),
    ("relaxation_time <= 0", {"halfspace.relaxation_time": 0},
     r"halfspace\.relaxation_time must be t' = eta / G, a finite number > 0 \[s\], got 0"),
    ("retardation_time <= 0", {"halfspace": {**VE, "creep": "kelvin_voigt",
                                             "retardation_time": -2.0}},
     r"halfspace\.retardation_time must be tau, a finite number > 0 \[s\], got -2\.0"),
    ("zener relaxed_young >= young", {"halfspace": {**VE, "creep": "zener",
                                                    "relaxed_young": 100e9,
                                                    "retardation_time": 1.0}},
     r"halfspace\.relaxed_young must be below halfspace\.young = 1e\+11 Pa"),
    ("prony terms not pairs", {"halfspace": {**VE, "creep": "prony", "terms": [0.5, 1.0]}},
     r"halfspace\.terms must be a non-empty list of \[c, tau\] pairs with c > 0 and "
     r"tau > 0 \[s\], got \[0\.5, 1\.0\]"),
    ("prony terms empty", {"halfspace": {**VE, "creep": "prony", "terms": []}},
     r"halfspace\.terms must be a non-empty list"),
    ("prony tau negative", {"halfspace": {**VE, "creep": "prony", "terms": [[0.5, -1.0]]}},
     r"halfspace\.terms must be .*got \[\[0\.5, -1\.0\]\]"),
    ("table not starting at 0", {"halfspace": {**VE, "creep": "tabulated",
                                               "table": [[0.1, 1.0], [1.0, 2.0]]}},
     r"halfspace\.table must start at t = 0, got t = 0\.1 s"),
    ("table not ascending", {"halfspace": {**VE, "creep": "tabulated",
                                           "table": [[0, 1.0], [2.0, 2.0], [1.0, 3.0]]}},
     r"halfspace\.table times must be strictly ascending"),
    ("table phi decreasing", {"halfspace": {**VE, "creep": "tabulated",
                                            "table": [[0, 1.0], [1.0, 0.5]]}},
     r"halfspace\.table phi must not decrease"),
    ("table phi zero after 0", {"halfspace": {**VE, "creep": "tabulated",
                                              "table": [[0, 0.0], [1.0, 0.0], [2.0, 1.0]]}},
     r"halfspace\.table phi must be > 0 \(it may be 0 at t = 0 only\)"),
    ("table of one row", {"halfspace": {**VE, "creep": "tabulated", "table": [[0, 1.0]]}},
     r"halfspace\.table must be a list of at least 2 \[t, phi\] rows"),
    ("both bodies rigid", {"halfspace": {"material": "rigid"}},
     r"indenter\.material and halfspace\.material are both 'rigid'"),
    # load
    ("time not increasing", {"load.time": [0.0, 0.6, 0.2, 1.0]},
     r"load\.time must be strictly increasing, got \[0\.0, 0\.6, 0\.2, 1\.0\] "
     r"\(time\[2\] = 0\.2 s <= time\[1\] = 0\.6 s\)"),
    ("time empty", {"load.time": []},
     r"load\.time must be a list of at least 1 strictly increasing times \[s\], got \[\]"),
    ("normal force negative", {"load.normal_force": -5.0},
     r"load\.normal_force must be a force >= 0 \[N\] .*got -5\.0"),
    ("normal force zero", {"load.normal_force": 0},
     r"load\.normal_force = 0: zero normal force leaves nothing in contact"),
    ("normal force all zero", {"load.normal_force": [0, 0, 0, 0],
                               "load.tangential_force": DELETE},
     r"load\.normal_force is zero at every knot"),
    ("normal force wrong length", {"load.normal_force": [1000.0, 1000.0]},
     r"load\.normal_force has 2 values but load\.time has 4 knots"),
    ("normal force a string", {"load.normal_force": "1 kN"},
     r"load\.normal_force must be .*got '1 kN' \(a string\)"),
    ("tangential wrong length", {"load.tangential_force": [0.0, 90.0]},
     r"load\.tangential_force has 2 values but load\.time has 4 knots"),
    ("tangential mixed shape", {"load.tangential_force": [0.0, [90.0, 0.0], -90.0, 90.0]},
     r"load\.tangential_force must be a list of forces \[N\] along x1 or a list of "
     r"\[T1, T2\] pairs"),
    ("tangential pairs of three", {"load.tangential_force": [[0, 0, 0]] * 4},
     r"load\.tangential_force must be a list of forces"),
    ("fretting with time", {**FRETTING, "load.time": [0.0, 1.0]},
     r"load\.time = \[0\.0, 1\.0\] cannot be given with load\.fretting"),
    ("fretting with tangential_force", {**FRETTING, "load.tangential_force": [0.0, 1.0]},
     r"load\.tangential_force = .* cannot be given with load\.fretting"),
    ("fretting without window", {**FRETTING, "load.fretting": {"amplitude": 90.0}},
     r"load\.fretting\.window is required: tau, the total duration"),
    ("fretting cycles 0", {**FRETTING, "load.fretting": {"amplitude": 9.0, "window": 1.0,
                                                         "cycles": 0}},
     r"load\.fretting\.cycles must be an integer from 1 to 100000, got 0"),
    ("fretting with a listed normal force", {**FRETTING, "load.normal_force": [1.0, 2.0]},
     r"load\.normal_force must be a scalar \(a step at t = 0\) with load\.fretting"),
    # friction and gross sliding
    ("mu negative", {"friction.mu": -0.1},
     r"friction\.mu must be a finite number >= 0, got -0\.1"),
    ("mu infinite", {"friction.mu": float("inf")}, r"friction\.mu must be .*, got inf"),
    ("gross sliding", {"load.tangential_force": [0.0, 120.0, -90.0, 90.0]},
     r"^load\.tangential_force reaches 120 N at t = 0\.2 s, above friction\.mu \* W = 100 N "
     r"\(mu = 0\.1, load\.normal_force W = 1000 N\): gross sliding has no static solution\. "
     r"Lower the force or raise mu\.$"),
    ("gross sliding at mu * W exactly", {"load.tangential_force": [0.0, 100.0, -90.0, 90.0],
                                         "friction.mu": 0.125, "load.normal_force": 800.0},
     r"load\.tangential_force reaches 100 N at t = 0\.2 s, equal to friction\.mu \* W = "
     r"100 N"),
    ("tangential force without friction", {"friction": DELETE},
     r"load\.tangential_force reaches 90 N at t = 0\.2 s, above friction\.mu \* W = 0 N"),
    ("gross sliding as W falls", {"load.normal_force": [1000.0, 1000.0, 1000.0, 500.0]},
     r"load\.tangential_force reaches 90 N at t = 1 s, above friction\.mu \* W = 50 N"),
    ("gross sliding in two axes", {"load.tangential_force": [[0, 0], [60, 80.5], [0, 0],
                                                             [0, 0]]},
     r"load\.tangential_force reaches 100\.\d* N at t = 0\.2 s, above"),
    ("fretting amplitude too high", {**FRETTING, "load.fretting": {"amplitude": 150.0,
                                                                   "window": 1.0}},
     r"load\.fretting\.amplitude reaches 150 N at t = 0\.2 s, above friction\.mu \* W"),
    # grid and time
    ("grid points < 8", {"grid.points": [4, 24]},
     r"grid\.points must be two integers \[N1, N2\], each from 8 to 4096, got \[4, 24\]"),
    ("grid points > 4096", {"grid.points": [8192, 24]}, r"grid\.points must be .*got \[8192"),
    ("grid points not integers", {"grid.points": [24.0, 24.5]},
     r"grid\.points must be .*got \[24\.0, 24\.5\]"),
    ("grid points a scalar", {"grid.points": 24}, r"grid\.points must be .*got 24"),
    ("grid size <= 0", {"grid.size": [2e-3, 0.0]},
     r"grid\.size must be two numbers from 1e-09 to 1000 \[m\], \[L1, L2\] the full side "
     r"lengths, or 'auto', got \[0\.002, 0\.0\]"),
    ("grid size a word", {"grid.size": "big"}, r"grid\.size must be .*got 'big'"),
    ("time steps < 1", {"time.steps": 0}, r"time\.steps must be an integer >= 1, got 0"),
    ("time steps negative", {"time.steps": -3}, r"time\.steps must be an integer >= 1"),
    ("time steps float", {"time.steps": 20.0}, r"time\.steps must be an integer .*got 20\.0"),
    # solver and output
    ("tolerance too loose", {"solver.tolerance": 0.1},
     r"solver\.tolerance must be a number in \(0, 0\.01\], got 0\.1"),
    ("tolerance zero", {"solver.tolerance": 0}, r"solver\.tolerance must be .*got 0"),
    ("max_iterations < 1", {"solver.max_iterations": 0},
     r"solver\.max_iterations must be an integer >= 1, got 0"),
    ("threads < 1", {"solver.threads": 0}, r"solver\.threads must be an integer >= 1"),
    ("stride < 1", {"output.stride": 0}, r"output\.stride must be an integer >= 1, got 0"),
    ("step_start with kelvin_voigt", {"solver.time_rule": "step_start",
                                      "halfspace": {**VE, "creep": "kelvin_voigt",
                                                    "retardation_time": 1.0}},
     r"solver\.time_rule = 'step_start' with halfspace\.creep = 'kelvin_voigt' \(phi\(0\) = "
     r"0, no instantaneous elasticity\): the step-start rule gives a rigid response\. Use "
     r"time_rule = \"auto\""),
    # the paper's step-start rule is explicit: Maxwell t' = 0.5 s is stable for steps
    # below 2 t' = 1 s; the scene's window of 1 s in 1 step is at the bound (issue 9)
    ("step_start above its stability bound",
     {"solver.time_rule": "step_start", "time.steps": 1,
      "halfspace": {**VE, "creep": "maxwell", "relaxation_time": 0.5}},
     r"^solver\.time_rule = 'step_start' is unstable for halfspace\.creep = 'maxwell': the "
     r"time step 1 s is not below its stability bound 1 s \(the error grows every step\); "
     r"take time\.steps >= 2 or solver\.time_rule = \"auto\"$"),
    ("creep table shorter than the window", {"halfspace": {**VE, "creep": "tabulated",
                                                          "table": [[0, 1.0], [0.5, 2.0]]}},
     r"^halfspace\.table ends at t = 0\.5 s, before the end of the load window \(load\.time "
     r"spans 1 s\): phi\(t\) is not known past the table's last row; extend the table to "
     r"t >= 1 s$"),
    # absurd sizes: capped, the cap said
    ("time steps absurd", {"time.steps": 10**9},
     r"^time\.steps = 1000000000 is above the cap of 1000000: each step is a full contact "
     r"solve"),
    ("preload substeps absurd", {"solver.preload_substeps": 10**9},
     r"^solver\.preload_substeps = 1000000000 is above the cap of 10000"),
    ("fretting cycles absurd", {**FRETTING, "load.fretting": {"amplitude": 9.0, "window": 1.0,
                                                              "cycles": 10**9}},
     r"load\.fretting\.cycles must be an integer from 1 to 100000, got 1000000000"),
    ("threads absurd", {"solver.threads": 10**6},
     r"^solver\.threads = 1000000 is above the cap of 1024"),
    ("stride absurd", {"output.stride": 10**12},
     r"^output\.stride = 1000000000000 is above the cap of 1000000"),
    ("time of an infinite span", {"load.time": [-1e308, 0.0, 1e308, 1.7e308]},
     r"load\.time spans -1e\+308 to 1\.7e\+308 s, a duration beyond the range of a float"),
    ("knots on no uniform mesh", {"time": DELETE, "load.time": [0.0, 1 / np.pi, 0.6, 1.0]},
     r"^time\.steps is required here: no uniform mesh of at most 1000000 steps holds every "
     r"load knot \(load\.time = \[0\.0, 0\.3183"),
    ("step_start with a table from phi = 0", {
        "solver.time_rule": "step_start", "halfspace": {"material": "rigid"},
        "indenter": {**VE, "creep": "tabulated", "table": [[0, 0.0], [1.0, 1.0]]}},
     r"solver\.time_rule = 'step_start' with indenter\.creep = 'tabulated' \(phi\(0\) = 0"),
]


@pytest.mark.parametrize("changes, match", [m[1:] for m in MISTAKES],
                         ids=[m[0] for m in MISTAKES])
def test_mistake(changes, match):
    with pytest.raises(SceneError, match=match) as info:
        scene_with(changes)
    assert isinstance(info.value, ValueError)


def test_the_mistakes_are_distinct():
    assert len({m[0] for m in MISTAKES}) == len(MISTAKES) >= 20


def test_every_problem_is_reported_at_once():
    with pytest.raises(SceneError) as info:
        scene_with({"geometry.radius": -1, "halfspace.poisson": 0.7, "friction.mu": "high",
                    "grid.points": [4, 4], "solver.tolerance": 1.0, "output.stride": 0,
                    "colour": "red"})
    problems = info.value.problems
    assert len(problems) == 7
    for field in ("geometry.radius", "halfspace.poisson", "friction.mu", "grid.points",
                  "solver.tolerance", "output.stride", "'colour'"):
        assert sum(field in p for p in problems) == 1, field
    assert str(info.value).startswith("7 problems: ")


def test_a_single_problem_is_the_message():
    with pytest.raises(SceneError) as info:
        scene_with({"friction.mu": -1})
    assert str(info.value) == "friction.mu must be a finite number >= 0, got -1"


def test_auto_grid_is_refused_for_a_surface(tmp_path):
    np.save(tmp_path / "g.npy", np.zeros((24, 24)))
    with pytest.raises(SceneError, match=r"grid\.size = 'auto' is not available for "
                                         r"geometry\.shape = 'surface'"):
        scene_with({"geometry": {"shape": "surface", "file": str(tmp_path / "g.npy")},
                    "grid.size": "auto"})


def test_surface_npy_must_match_the_grid(tmp_path):
    np.save(tmp_path / "g.npy", np.zeros((32, 24)))
    with pytest.raises(SceneError, match=r"geometry\.file '.*g\.npy': array of shape "
                                         r"\(32, 24\), but grid\.points is \[24, 24\]"):
        scene_with({"geometry": {"shape": "surface", "file": str(tmp_path / "g.npy")}})


def test_surface_netcdf_needs_a_gap_variable(tmp_path):
    xr = pytest.importorskip("xarray")
    x = np.linspace(-2e-3, 2e-3, 5)
    xr.Dataset({"height": (("x1", "x2"), np.zeros((5, 5)))},
               coords={"x1": x, "x2": x}).to_netcdf(tmp_path / "h.nc")
    with pytest.raises(SceneError, match=r"geometry\.file '.*h\.nc': no variable 'gap'"):
        scene_with({"geometry": {"shape": "surface", "file": str(tmp_path / "h.nc")}})


def test_surface_netcdf_must_cover_the_grid(tmp_path):
    xr = pytest.importorskip("xarray")
    x = np.linspace(-5e-4, 5e-4, 5)
    xr.Dataset({"gap": (("x1", "x2"), np.zeros((5, 5)))},
               coords={"x1": x, "x2": x}).to_netcdf(tmp_path / "s.nc")
    with pytest.raises(SceneError, match=r"geometry\.file '.*s\.nc': does not cover the "
                                         r"grid: the grid's x1 .* outside the file's x1"):
        scene_with({"geometry": {"shape": "surface", "file": str(tmp_path / "s.nc")}})


def test_parts_constructed_alone_are_validated():
    with pytest.raises(SceneError, match=r"geometry\.radius must be a finite number > 0"):
        Geometry("sphere", radius=-1.0)
    with pytest.raises(SceneError, match=r"friction\.mu must be"):
        Friction(mu=float("nan"))
    with pytest.raises(SceneError, match=r"body\.poisson must be a number in \[0, 0\.5\]"):
        BodySpec("elastic", young=1e9, poisson=0.6)
    with pytest.raises(SceneError, match=r"grid\.points must be"):
        Grid(points=(2, 2), size=(1e-3, 1e-3))
    with pytest.raises(SceneError, match=r"load\.normal_force is required"):
        Load(time=[0.0, 1.0])


def test_not_a_scene():
    with pytest.raises(SceneError, match=r"a scene must be a table \(dict\), got \[1, 2\]"):
        Scene.from_dict([1, 2])
    with pytest.raises(SceneError, match=r"changes must be a dict of dotted paths"):
        scene_with({}).replace(["friction.mu", 0.2])
    with pytest.raises(SceneError, match=re.escape("change '': a change's key must be a "
                                                   "dotted path")):
        scene_with({}).replace({"": 1})


def test_invalid_toml_names_the_file(tmp_path):
    p = tmp_path / "broken.toml"
    p.write_text("[geometry\nshape = 'sphere'\n")
    with pytest.raises(SceneError, match=r"broken\.toml is not valid TOML"):
        Scene.from_toml(p)


# ----------------------------------------------------------------------------- small traps

def deep(n, leaf="x"):
    """A value nested ``n`` lists deep."""
    for _ in range(n):
        leaf = [leaf]
    return leaf


@pytest.mark.parametrize("path", ["name", "geometry.radius", "load.time", "grid.points",
                                  "halfspace.table", "friction", "load.tangential_force"])
def test_a_value_nested_5000_deep_is_one_line(path):
    with pytest.raises(SceneError) as info:
        scene_with({path: deep(5000)})
    msg = str(info.value)
    assert "\n" not in msg and len(msg) < 600 and path in msg


def test_toml_nested_5000_deep_is_one_line(tmp_path):
    text = "name = " + "[" * 5000 + "]" * 5000 + "\n"
    with pytest.raises(SceneError, match=r"^the scene is not valid TOML: arrays or tables "
                                         r"nested too deep to read"):
        Scene.from_toml_text(text)
    p = tmp_path / "deep.toml"
    p.write_text(text)
    with pytest.raises(SceneError, match=r"deep\.toml is not valid TOML: arrays or tables"):
        Scene.from_toml(p)
    from contactpipe._util.files import read_toml
    with pytest.raises(SceneError, match=r"deep\.toml is not a valid TOML sweep file: arrays"):
        read_toml(p, "sweep")


TINY = """name = "t"
[geometry]
shape = "sphere"
radius = 0.018
[indenter]
material = "rigid"
[halfspace]
material = "elastic"
young = 105e9
poisson = 0.3
[friction]
mu = 0.1
[load]
normal_force = 1000.0
{load}
[grid]
points = [24, 24]
size = [2.0e-3, 2.0e-3]
{extra}
"""
EXPLICIT = "time = [0.0, 0.2, 0.6, 1.0]\ntangential_force = [0.0, 90.0, -90.0, 90.0]"
PRESET = "fretting = {amplitude = 90.0, window = 1.0}"

#: (id, the [load] lines, more tables, a file the scene refers to or None, message)
BAD_FILES = [
    ("steps 1e9", EXPLICIT, "[time]\nsteps = 1000000000", None,
     "time.steps = 1000000000 is above the cap of 1000000"),
    ("preload substeps 1e9", EXPLICIT, "[solver]\npreload_substeps = 1000000000", None,
     "solver.preload_substeps = 1000000000 is above the cap of 10000"),
    ("fretting cycles 1e9", "fretting = {amplitude = 90.0, window = 1.0, cycles = 1000000000}",
     "", None, "load.fretting.cycles must be an integer from 1 to 100000"),
    ("knots on no mesh", "time = [0.0, 0.3183098861837907, 1.0]\n"
                         "tangential_force = [0.0, 90.0, 0.0]", "", None,
     "time.steps is required here"),
    ("complex gap", PRESET, "", np.zeros((24, 24), complex), "(a complex gap has no meaning)"),
    ("gap with NaN", PRESET, "", np.full((24, 24), np.nan), "the gap holds NaN or inf"),
    ("creep table too short", PRESET, "", None, "halfspace.table ends at t = 0.5 s"),
    ("name nested 5000 deep", PRESET, "", None, "is not valid TOML: arrays or tables nested"),
]


@pytest.mark.parametrize("load, extra, gap, message", [b[1:] for b in BAD_FILES],
                         ids=[b[0] for b in BAD_FILES])
def test_bad_scene_file_is_one_line_exit_2_and_no_file(tmp_path, capsys, load, extra, gap,
                                                       message):
    from contactpipe.pipeline import cli
    text = TINY.format(load=load, extra=extra)
    if gap is not None:
        np.save(tmp_path / "gap.npy", gap)
        text = text.replace('shape = "sphere"\nradius = 0.018', 'shape = "surface"\n'
                                                                'file = "gap.npy"')
    if message.startswith("halfspace.table"):
        text = text.replace('material = "elastic"', 'material = "viscoelastic"\n'
                            'creep = "tabulated"\ntable = [[0.0, 1.0], [0.5, 2.0]]')
    if "nested" in message:
        text = text.replace('name = "t"', "name = " + "[" * 5000 + "]" * 5000)
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    before = sorted(tmp_path.iterdir())
    out = tmp_path / "x.nc"
    assert cli.main(["run", str(scene), "-o", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("contactpipe: error: "), err[:2000]
    assert message in err
    assert sorted(tmp_path.iterdir()) == before and not out.exists()


def test_deep_name_through_the_console_is_one_line(tmp_path):
    """The issue's case in a fresh process: a 3002-line RecursionError before."""
    import subprocess
    import sys
    scene = tmp_path / "bad.toml"
    scene.write_text(TINY.format(load=PRESET, extra="").replace(
        'name = "t"', "name = " + "[" * 5000 + "]" * 5000))
    r = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", "run", str(scene),
                        "-o", str(tmp_path / "x.nc")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr[-2000:]
    assert "nested too deep" in r.stderr and not (tmp_path / "x.nc").exists()


@pytest.mark.parametrize("fields, call, key", [
    (dict(material="viscoelastic", creep="maxwell", young=1e9, poisson=0.3),
     "creep_function", "body.relaxation_time is required for material = 'viscoelastic', "
                       "creep = 'maxwell'"),
    (dict(material="viscoelastic", creep="zener", young=3e9, poisson=0.3,
          retardation_time=1.0), "creep_function", "body.relaxed_young is required"),
    (dict(material="elastic", poisson=0.3), "body",
     "body.young is required for material = 'elastic', and is not given"),
])
def test_a_body_built_without_a_required_key_names_it(fields, call, key):
    """A body spec made without validation (BodySpec.make) and missing a key its model
    needs: a SceneError naming the key, not a TypeError deep in materials (maxwell) or a
    Body whose young modulus is None (elastic), as before."""
    spec = BodySpec.make(**fields)
    with pytest.raises(SceneError, match=re.escape(key)):
        getattr(spec, call)()
