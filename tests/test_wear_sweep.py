"""Wear scenes sweep like any other: cp.sweep over a [wear] scene, and open_sweep combines
the members with the wear history over ``cycle`` intact (the union of the members'
recorded cycles; a member's value where it recorded, NaN where it did not)."""
import numpy as np
import pytest

import contactpipe as cp

MUS = [0.6, 1.0]


def _scene(jump):
    steel = {"material": "elastic", "young": 210e9, "poisson": 0.3}
    return cp.Scene(
        name="wear-sweep", geometry={"shape": "sphere", "radius": 0.018},
        indenter=dict(steel), halfspace=dict(steel), friction={"mu": 0.3},
        load={"time": [0, 0.25, 0.5, 0.75, 1.0], "normal_force": 1000.0,
              "tangential_force": [0, 150, 0, -150, 0]},
        grid={"points": [16, 16], "size": [1.6e-3, 1.6e-3]}, time={"steps": 8},
        wear={"law": "archard", "coefficient": 1e-12, "cycles": 20, "jump": jump})


@pytest.mark.parametrize("jump", ["auto", 1])
def test_sweep_of_a_wear_scene_keeps_the_cycle_dimension(tmp_path, jump):
    base = _scene(jump)
    cp.sweep(base, {"friction.mu": MUS}, tmp_path, scheduler="synchronous", progress=False)
    sw = cp.open_sweep(tmp_path)
    try:
        assert sw["wear_depth"].dims == ("mu", "cycle", "x1", "x2")
        for name in ("worn_volume", "cumulative_dissipation", "cycle_p_max",
                     "cycle_stick_area"):
            assert sw[name].dims == ("mu", "cycle"), name
        assert sw["p"].dims == ("mu", "time", "x1", "x2")       # the last simulated cycle
        assert sw["cycle"].dtype.kind == "i" and sw["cycle"].values[0] == 1
        assert sw["cycle"].values[-1] == 20
        records = set()
        for mu in MUS:
            member = cp.open_archive(tmp_path / f"{base.replace({'friction.mu': mu}).digest()}.nc")
            with member:
                mine = member["cycle"].values
                records |= set(mine.tolist())
                got = sw.sel(mu=mu)
                np.testing.assert_array_equal(got["worn_volume"].sel(cycle=mine).values,
                                              member["worn_volume"].values)
                np.testing.assert_array_equal(got["wear_depth"].sel(cycle=mine).values,
                                              member["wear_depth"].values)
                others = np.setdiff1d(sw["cycle"].values, mine)
                assert np.all(np.isnan(got["worn_volume"].sel(cycle=others).values))
                assert got.attrs.get("wear_law", member.attrs["wear_law"]) == "archard"
        assert sorted(records) == sw["cycle"].values.tolist()
        if jump == 1:            # every member records the same cycles: no hole
            assert not np.any(np.isnan(sw["worn_volume"].values))
        # the lower friction slips more and wears more
        assert float(sw["worn_volume"].sel(mu=0.6, cycle=20)) > \
            float(sw["worn_volume"].sel(mu=1.0, cycle=20))
    finally:
        sw.close()


def test_pipeline_runs_a_wear_sweep(tmp_path, capsys):
    """contactpipe pipeline over the same wear scene: the members are not compared (no
    closed form describes a worn contact: not a failure), each gets its wear figure, and
    the sweep overlay draws the worn volume against cycles."""
    from contactpipe.pipeline.cli import main as cli_main
    (tmp_path / "base.toml").write_text(_scene("auto").to_toml())
    (tmp_path / "pipeline.toml").write_text(
        'name = "wear-pipe"\nout = "runs"\n[sweep]\nbase = "base.toml"\n'
        '[sweep.axes]\n"friction.mu" = [0.6, 1.0]\n'
        '[plot]\nfigures = ["wear", "hysteresis", "sweep"]\n'
        'variables = ["worn_volume", "contact_area"]\n')
    assert cli_main(["pipeline", str(tmp_path / "pipeline.toml"), "--scheduler",
                     "synchronous", "--no-progress"]) == 0
    assert "0 failed" in capsys.readouterr().out
    figs = sorted(p.name for p in (tmp_path / "runs" / "figures").glob("*.png"))
    assert sum(f.endswith("-wear.png") for f in figs) == 2
    assert "sweep-worn_volume.png" in figs and "sweep-contact_area.png" in figs
    assert not (tmp_path / "runs" / "compare").exists() or \
        not list((tmp_path / "runs" / "compare").glob("*.nc"))


def test_no_closed_form_describes_a_wear_run():
    """The Mindlin-Deresiewicz closed form fits the scene without [wear], not with it."""
    from contactpipe.pipeline.compare.reference import diagnose
    worn = _scene("auto")
    name, why = diagnose(worn)
    assert name is None and all("[wear]" in r[0] for r in why.values())
    plain = cp.Scene(**{k: v for k, v in worn.to_dict().items() if k != "wear"})
    assert diagnose(plain)[0] == "mindlin_deresiewicz"
