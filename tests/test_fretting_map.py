"""Fretting maps (issue 10 item 6): the closed-form boundary and energy ratio, the
classification of a loop by Fouvry's energy ratio (contactpipe.post.fretting), the derived
sweep parameters delta_amplitude / delta_ratio, the regime table of a sweep and the
``fretting-map`` plot kind.

Steel on steel, R = 18 mm, W = 1 kN (Hertz a = 0.489 mm), mu = 0.1: delta_gs = 1.61 um.
"""
import pathlib

import numpy as np
import pytest
from helpers import A_HERTZ, E_STAR_STEEL, MU, R, W, make_scene

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.exceptions import ArchiveError, SceneError
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.pipeline.figures.fretting import plot_energy_ratio, plot_fretting_map
from contactpipe.pipeline.figures.regimes import fretting_map, write_regime_table
from contactpipe.pipeline.sweep.parameters import delta_amplitude, delta_ratio
from contactpipe.post.fretting import classify_loop, fretting_regime, loop_cycles, turning_points

C_SUM = an.tangential_compliance_sum(210e9, 0.3, 210e9, 0.3)
D_GS = an.gross_slip_displacement(MU, W, A_HERTZ, C_SUM)
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def displacement_scene(knots, n=32, per_interval=8, mu=MU):
    """omega1 through ``knots`` (x delta_gs), one knot per second, n² over 3 a."""
    return make_scene(friction={"mu": mu},
                      load={"time": [float(i) for i in range(len(knots))],
                            "normal_force": W,
                            "tangential_displacement": [k * D_GS for k in knots]},
                      grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                      time={"steps": per_interval * (len(knots) - 1)})


def cycle(amplitude, n=32, per_quarter=8):
    """0 -> d -> -d -> d (d = amplitude x delta_gs), ``per_quarter`` steps per quarter."""
    return make_scene(friction={"mu": MU},
                      load={"time": [0.0, 1.0, 3.0, 5.0], "normal_force": W,
                            "tangential_displacement": [0.0, amplitude * D_GS,
                                                        -amplitude * D_GS, amplitude * D_GS]},
                      grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                      time={"steps": 5 * per_quarter})


# --------------------------------------------------------------------------- closed forms
def test_boundary_is_delta_gs():
    """gross_slip_boundary(mu, W) = 3 mu W (2 - nu)/(8 G a(W)) for identical bodies, over
    arrays of mu and W (1e-14); for steel on aluminium the compliance form
    gross_slip_displacement with the pair's Hertz radius (1e-14); W <= 0 is refused."""
    G = 210e9 / 2.6
    mus = np.array([0.05, 0.1, 0.3])
    forces = np.array([[250.0], [1000.0]])
    d = an.gross_slip_boundary(mus, forces, R, E_STAR_STEEL, C_SUM)
    a = (3 * forces * R / (4 * E_STAR_STEEL)) ** (1 / 3)
    np.testing.assert_allclose(d, 3 * mus * forces * (2 - 0.3) / (8 * G * a), rtol=1e-14)
    assert an.gross_slip_boundary(MU, W, R, E_STAR_STEEL, C_SUM) == pytest.approx(D_GS,
                                                                                rel=1e-14)
    e_star = an.composite_modulus(210e9, 0.3, 70e9, 0.33)
    c_sum = an.tangential_compliance_sum(210e9, 0.3, 70e9, 0.33)
    a_al = an.hertz_sphere(W, R, e_star).contact_radius
    assert an.gross_slip_boundary(MU, W, R, e_star, c_sum) == pytest.approx(
        an.gross_slip_displacement(MU, W, a_al, c_sum), rel=1e-14)
    with pytest.raises(ValueError, match="W > 0"):
        an.gross_slip_boundary(MU, 0.0, R, E_STAR_STEEL, C_SUM)


def test_energy_ratio_closed_form():
    """A(x) = E(delta*)/(4 T(delta*) delta*) from displacement_energy_per_cycle and
    mindlin_force (1e-9 for x >= 0.01, where the latter's own cancellation allows it);
    exactly 0.2 at x = 1 (Fouvry's transition), 1 - 0.8/x beyond, x/12 as x -> 0 (1e-5 at
    x = 1e-6), increasing."""
    for x in [0.01, 0.04, 0.05, 0.1, 0.3, 0.7, 0.95, 0.999, 1.5, 3.0, 10.0]:
        d = x * D_GS
        ref = an.displacement_energy_per_cycle(d, MU, W, A_HERTZ, C_SUM) / (
            4 * an.mindlin_force(d, MU, W, A_HERTZ, C_SUM) * d)
        assert an.energy_ratio(x) == pytest.approx(ref, rel=1e-9)
    assert an.energy_ratio(1.0) == pytest.approx(0.2, rel=1e-15)
    assert an.ENERGY_RATIO_TRANSITION == 0.2
    assert an.energy_ratio(4.0) == pytest.approx(0.8, rel=1e-15)
    assert an.energy_ratio(1e-6) == pytest.approx(1e-6 / 12, rel=1e-5)
    assert an.energy_ratio(0.0) == 0.0
    grid = np.linspace(0, 5, 2001)
    assert np.all(np.diff(an.energy_ratio(grid)) > 0)


# --------------------------------------------------------------------------- loops
def closed_form_loop(knots, per=400):
    """omega (x delta_gs knots, ``per`` samples per interval) and the closed-form T."""
    om = np.concatenate([np.linspace(a, b, per + 1)[:-1]
                         for a, b in zip(knots[:-1], knots[1:], strict=True)]
                        + [np.array(knots[-1:])]) * D_GS
    return om, an.displacement_loop_force(om, MU, W, A_HERTZ, C_SUM)


def test_cycles_of_a_history():
    """Turning points skip holds; cycles are pairs two turning points apart at the same
    displacement."""
    d = [0.0, 1.0, 2.0, 2.0, 1.0, -2.0, -2.0, 0.0, 2.0, 1.0]
    assert list(turning_points(d)) == [0, 2, 5, 8, 9]
    assert loop_cycles(d) == [(2, 8)]
    assert loop_cycles([0.0, 1.0, -1.0]) == []


@pytest.mark.parametrize("x", [0.3, 0.9, 1.2, 3.0])
def test_closed_form_loop_is_classified_as_its_amplitude(x):
    """The closed-form loop of amplitude x delta_gs, 400 samples per quarter: A within
    1e-4 of energy_ratio(x) (trapezoids), the regime that of x against 1, and the closed-
    form columns filled from delta_gs."""
    om, T = closed_form_loop([0.0, x, -x, x])
    r = classify_loop(om, T, D_GS)
    assert r.ratio == pytest.approx(an.energy_ratio(x), rel=1e-4)
    assert r.delta_star == pytest.approx(x * D_GS, rel=1e-12)
    want = "gross slip" if x > 1 else "partial slip"
    assert r.regime == want and r.regime_closed_form == want
    assert r.ratio_closed_form == pytest.approx(an.energy_ratio(x), rel=1e-12)


def test_a_loop_that_changes_regime_is_mixed():
    """A cycle at 2 delta_gs then one at 0.5 delta_gs: gross slip, then partial slip ->
    mixed (and so is the closed form); the second loop, offset by the slide, still has
    A = energy_ratio(0.5) (1e-4: T* is half the force range)."""
    om, T = closed_form_loop([0.0, 2.0, -2.0, 2.0, -0.5, 0.5, -0.5])
    r = classify_loop(om, T, D_GS)
    assert [c.regime for c in r.cycles] == ["gross slip", "partial slip"]
    assert r.regime == "mixed" and r.regime_closed_form == "mixed"
    assert r.ratio == pytest.approx(an.energy_ratio(0.5), rel=1e-4)
    with pytest.raises(ValueError, match="no closed cycle"):
        classify_loop([0.0, 1.0, -1.0], [0.0, 1.0, -1.0])


def test_simulated_members_against_the_closed_form():
    """Simulated cycles at 0.5 and 2 delta_gs (32² over 3 a, 8 steps per quarter): partial
    and gross slip as the closed form says; A from the archive's loop (trapezoids) within
    3 % of energy_ratio (measured -0.86 % and -0.30 %: the trapezoids cut the curved
    branches)."""
    for x, want in ((0.5, "partial slip"), (2.0, "gross slip")):
        r = fretting_regime(cp.simulate(cycle(x)))
        assert r.regime == want and r.regime_closed_form == want
        assert r.delta_gs == pytest.approx(D_GS, rel=1e-12)
        assert r.ratio == pytest.approx(an.energy_ratio(x), rel=0.03)
        assert r.friction_coefficient == MU and r.normal_force == W


def test_simulated_mixed_member():
    """0 -> 2 -> -2 -> 2 -> -0.5 -> 0.5 -> -0.5 delta_gs on 16², 4 steps per interval:
    mixed, its cycles gross then partial slip."""
    r = fretting_regime(cp.simulate(displacement_scene([0, 2, -2, 2, -0.5, 0.5, -0.5], n=16,
                                                       per_interval=4)))
    assert [c.regime for c in r.cycles] == ["gross slip", "partial slip"]
    assert r.regime == "mixed"


def test_an_archive_without_a_cycle_is_refused():
    """A frictionless archive has no loop; a single tangential ramp has no closed cycle."""
    with pytest.raises(ArchiveError, match="not a fretting loop"):
        fretting_regime(cp.simulate(make_scene(grid={"points": [16, 16]})))
    with pytest.raises(ArchiveError, match="no closed cycle"):
        fretting_regime(cp.simulate(displacement_scene([0.0, 0.5], n=16, per_interval=2)))


# --------------------------------------------------------------------------- parameters
def test_derived_amplitude_parameters():
    """delta_amplitude scales the program to the largest |omega| given; delta_ratio to a
    multiple of the member's delta_gs (mu swept first: it moves); both refuse a base
    scene without a displacement program, delta_ratio one without a closed form."""
    base = cycle(1.0)
    assert delta_amplitude(base, 3e-6).load.tangential_displacement == \
        pytest.approx((0.0, 3e-6, -3e-6, 3e-6), rel=1e-14)
    s = delta_ratio(base.replace({"friction.mu": 0.2}), 2.0)
    assert max(s.load.tangential_displacement) == pytest.approx(4 * D_GS, rel=1e-12)
    with pytest.raises(SceneError, match="no load.tangential_displacement"):
        delta_amplitude(make_scene(), 1e-6)
    with pytest.raises(SceneError, match="delta_ratio must be a finite number > 0"):
        delta_ratio(base, -1.0)
    flat = base.replace({"geometry": {"shape": "flat_punch", "radius": A_HERTZ}})
    with pytest.raises(SceneError, match="needs a sphere"):
        delta_ratio(flat, 1.0)


# --------------------------------------------------------------------------- sweep, plot
@pytest.fixture(scope="module")
def fretting_sweep(tmp_path_factory):
    """delta_ratio [0.5, 2] x mu [0.1, 0.2], 16² over 3 a, 4 steps per quarter, run in
    this process (scheduler "synchronous")."""
    out = tmp_path_factory.mktemp("fmap") / "sweep"
    res = cp.sweep(cycle(1.0, n=16, per_quarter=4),
                   {"delta_ratio": [0.5, 2.0], "friction.mu": [0.1, 0.2]}, out,
                   scheduler="synchronous", progress=False)
    assert res.ok
    return out


def test_regime_table_of_a_sweep(fretting_sweep, tmp_path):
    """Each member's regime is that of its delta_ratio, as the closed form says; A within
    5 % of energy_ratio on 16² with 4 steps per quarter (measured -2.4 % at 0.5, -1.2 % at
    2, for either mu); the table
    writes as CSV with one row per member."""
    table = fretting_map(fretting_sweep)
    assert table.sizes["member"] == 4
    x = np.asarray(table.delta_ratio.values)
    np.testing.assert_allclose(np.sort(np.unique(np.round(x, 9))), [0.5, 2.0], rtol=1e-9)
    regimes = np.asarray(table.regime.values).astype(str)
    assert list(regimes) == ["gross slip" if v > 1 else "partial slip" for v in x]
    assert list(np.asarray(table.regime_closed_form.values).astype(str)) == list(regimes)
    np.testing.assert_allclose(table.energy_ratio.values, an.energy_ratio(x), rtol=0.05)
    assert table.attrs["radius_m"] == R
    csv = write_regime_table(table, tmp_path / "map.csv")
    rows = [ln for ln in csv.read_text().splitlines() if not ln.startswith("#")]
    assert len(rows) == 5 and rows[0].startswith("member,mu,W,delta_star")
    with pytest.raises(ArchiveError, match="CSV"):
        write_regime_table(table, tmp_path / "map.nc")


def test_plot_functions_draw_into_given_axes(fretting_sweep):
    from matplotlib.figure import Figure  # matplotlib: only the figure tests need it
    fig = Figure()
    ax1, ax2 = fig.subplots(1, 2)
    assert plot_fretting_map(fretting_sweep, ax=ax1) is fig
    assert plot_energy_ratio(fretting_map(fretting_sweep), ax=ax2) is fig
    assert ax1.get_ylabel().startswith("friction coefficient")
    table = fretting_map(fretting_sweep)
    varied = table.assign(W=("member", [500.0, 1000.0, 500.0, 1000.0]))
    assert plot_fretting_map(varied, against="W").axes[0].get_ylabel().startswith(
        "normal force")
    # every member has W = 1000 N: a map against W would be one line of points
    with pytest.raises(ArchiveError, match=r"against = 'W': every member has W = 1000, "
                                           r"one value.*load.normal_force.*against = 'mu'"):
        plot_fretting_map(table, against="W")


def test_cli_fretting_map(fretting_sweep, tmp_path, capsys):
    """The plot kind end to end: a PNG; an archive or a sweep that is not a fretting loop
    is one line on stderr, exit 2, nothing written."""
    out = tmp_path / "map.png"
    assert cli_main(["plot", str(fretting_sweep), "--kind", "fretting-map", "-o",
                     str(out)]) == 0
    assert out.read_bytes()[:8] == PNG_MAGIC and out.stat().st_size > 10_000
    archive = next(pathlib.Path(fretting_sweep).glob("*.nc"))
    bad = tmp_path / "bad.png"
    capsys.readouterr()
    assert cli_main(["plot", str(archive), "--kind", "fretting-map", "-o", str(bad)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "--kind fretting-map does not apply to an archive" in err
    assert "a sweep folder takes sweep, fretting-map" in err and not bad.exists()
    plain = tmp_path / "plain"
    assert cp.sweep(make_scene(grid={"points": [16, 16]}), {"load.normal_force": [500.0]},
                    plain, scheduler="synchronous", progress=False).ok
    assert cli_main(["plot", str(plain), "--kind", "fretting-map", "-o", str(bad)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "not a fretting loop" in err
    assert not bad.exists()
    # --against W on a sweep of one W: refused, one line, exit 2, nothing written
    assert cli_main(["plot", str(fretting_sweep), "--kind", "fretting-map", "--against",
                     "W", "-o", str(bad)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "every member has W = 1000" in err
    assert "Traceback" not in err and not bad.exists()
