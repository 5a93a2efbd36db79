"""Partial slip and fretting on a rough sphere (a generated self-affine surface riding on
the paper's sphere), elastic and viscoelastic, free boundary, 48^2 cells: the contact
laws, the initial gap in the archive, the loop energy against the amplitude, memory, and
the stick and slip clusters."""
import numpy as np
import pytest
import xarray as xr
from helpers import A_HERTZ, MU, R, W, make_scene

import contactpipe as cp
from contactpipe.nomenclature import STATUS_SEPARATED, STATUS_SLIP, STATUS_STICK
from contactpipe.post.clusters import contact_clusters, count_clusters
from contactpipe.post.fretting import loop_energy
from contactpipe.testing import contact_law_violations

N = 48
SIDE = 3 * A_HERTZ
#: H = 0.8, rms slope 0.02, roll-off half the side, cut-off 6 cells, on R = 18 mm.
ROUGH = {"shape": "rough", "hurst": 0.8, "rms_slope": 0.02,
         "wavelengths": [SIDE / 2, 6 * SIDE / N], "seed": 1, "form": "sphere", "radius": R}
MAXWELL = {"material": "viscoelastic", "young": 210e9, "poisson": 0.3, "creep": "maxwell",
           "relaxation_time": 1.0}


def _loop(amplitude, steps=10, n=N, **over):
    """The fretting loop T: 0 -> +T* -> -T* -> +T*, T* = amplitude mu W, on the rough
    sphere of n^2 cells (steel on steel unless ``over`` says otherwise)."""
    ts = amplitude * MU * W
    return make_scene(geometry={**ROUGH, "wavelengths": [SIDE / 2, 6 * SIDE / n]},
                      friction={"mu": MU},
                      load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
                            "tangential_force": [0.0, ts, -ts, ts]},
                      grid={"points": [n, n], "size": [SIDE, SIDE]},
                      time={"steps": steps}, **over)


def _cycle_energy(ds):
    """The loop energy of the closed cycle from +T* (t = 0.2 s) back to +T* [J]."""
    k = int(np.argmin(np.abs(ds.time.values - 0.2)))
    return abs(loop_energy(ds.omega1.values[k:], ds.T1.values[k:]))


def test_fretting_loop_on_a_rough_sphere(tmp_path):
    """The streamed archive of a loop at T* = 0.6 mu W obeys the contact laws (1e-9), holds
    the initial gap h0 exactly as the scene makes it (least value 0), and has stick and
    slip at the loop's ends, in clusters that the post function counts."""
    scene = _loop(0.6)
    path = tmp_path / "rough.nc"
    cp.simulate(scene, path)
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    assert contact_law_violations(ds) == []
    gap = scene.geometry.gap(ds.x1.values, ds.x2.values)
    np.testing.assert_array_equal(ds["h0"].values, gap)
    assert ds["h0"].attrs["units"] == "m" and float(ds["h0"].min()) == 0.0
    counts = contact_clusters(ds)
    status = ds.status.values[-1]
    assert (status == STATUS_STICK).any() and (status == STATUS_SLIP).any()
    assert int(counts.stick_clusters[-1]) >= 1 and int(counts.slip_clusters[-1]) >= 1
    assert np.all(counts.contact_clusters.values >= 1)   # W is applied at t = 0


def test_cluster_count_on_a_known_map():
    """Four stick islands (two of them single cells touching at a corner only: apart)
    and one slip ring around one of them: stick 4, slip 1, contact 5 (the island inside
    the ring is cut off from it by open cells)."""
    s = np.full((9, 9), STATUS_SEPARATED, dtype=np.int8)
    s[1:6, 1:6] = STATUS_SLIP
    s[2:5, 2:5] = STATUS_SEPARATED
    s[3, 3] = STATUS_STICK
    s[7, 7] = STATUS_STICK
    s[8, 8] = STATUS_STICK                                # corner contact: apart
    s[7, 1:3] = STATUS_STICK
    ds = xr.Dataset({"status": (("time", "x1", "x2"), s[None])}, coords={"time": [0.0]})
    counts = contact_clusters(ds)
    assert int(counts.stick_clusters[0]) == 4
    assert int(counts.slip_clusters[0]) == 1
    assert int(counts.contact_clusters[0]) == 5
    assert count_clusters(s == STATUS_SLIP) == 1


def test_loop_energy_is_continuous_in_the_amplitude():
    """Six amplitudes T*/(mu W) = 0.3 x 1.2^k (0.30 to 0.75), 10 steps each: the loop
    energy grows strictly, and on a log-log scale each inner value lies within 0.1 of its
    neighbours' mean (a smooth curve at this step: 0.05 at most measured, Mindlin's closed
    form for a smooth sphere 0.03; a jump of 20 % at one amplitude would exceed 0.1)."""
    amps = 0.3 * 1.2 ** np.arange(6)
    energy = np.array([_cycle_energy(cp.simulate(_loop(a))) for a in amps])
    assert np.all(np.diff(energy) > 0)
    log = np.log(energy)
    assert np.max(np.abs(log[1:-1] - 0.5 * (log[:-2] + log[2:]))) <= 0.1


def test_memory_runs_on_a_rough_sphere():
    """A rigid rough sphere on a Maxwell half-space (t' = 1 s) through the loop: the
    contact laws hold, and under the constant W the contact area creeps: the Maxwell
    compliance doubles over the 1 s window, so the area at the end exceeds the area at
    the first loaded instant by more than 20 % (measured +38 %)."""
    ds = cp.simulate(_loop(0.5, indenter={"material": "rigid"}, halfspace=MAXWELL))
    assert contact_law_violations(ds) == []
    area = ds.contact_area.values
    assert area[-1] > 1.2 * area[1]



def test_a_512_rough_run_with_memory_is_refused_when_it_would_not_fit(monkeypatch,
                                                                       tmp_path):
    """512^2 free-boundary partial slip with memory on the rough sphere, 20 steps: the
    estimate holds the surface's h0 map (8 bytes a cell) and is about 3 kB a cell
    (benchmarks/bench_rough.py measures the run); with 1 byte less memory available than
    the estimate, cp.simulate refuses before the run starts, in one line naming the
    estimate, its figure per cell and the memory available; with the estimate available
    it would start."""
    from contactpipe.planning import resources

    scene = _loop(0.5, steps=20, n=512, indenter={"material": "rigid"}, halfspace=MAXWELL)
    est = resources.estimate_resources(scene)
    assert est.parts["surface"] == 512 ** 2 * 8
    assert 2000 < est.bytes_per_cell < 5000
    assert resources.check_resources(est, available=est.memory_bytes) is est

    def refuse(*args, **kwargs):
        raise AssertionError("the run started")
    monkeypatch.setattr(cp.simulation.march, "_run", refuse)
    monkeypatch.setattr(resources, "available_memory",
                        lambda: (est.memory_bytes - 1, "test limit"))
    with pytest.raises(cp.SceneError) as err:
        cp.simulate(scene, tmp_path / "big.nc")
    text = str(err.value)
    assert text.startswith("the run needs about ") and "\n" not in text
    assert f"({est.bytes_per_cell / 1024:.1f} KiB per cell;" in text
    assert "512x512 cells" in text and "available (test limit)" in text


def test_the_read_back_check_holds_a_small_chunk_cache(monkeypatch, tmp_path):
    """The written archive is read back with a 1 MiB chunk cache per variable, not the
    HDF5 library's 64 MiB, which kept every chunk read (at 512^2, 21 instants: 325 MiB
    above the estimate, measured); the library's default is restored afterwards."""
    import netCDF4

    from contactpipe.archive import writer

    seen = []
    real = writer.xr.open_dataset

    def spy(file, *args, **kwargs):
        if str(file).endswith(".part"):               # the writer's read-back check
            seen.append(netCDF4.get_chunk_cache()[0])
        return real(file, *args, **kwargs)
    default = netCDF4.get_chunk_cache()
    monkeypatch.setattr(writer.xr, "open_dataset", spy)
    cp.simulate(_loop(0.5, steps=5, n=16), tmp_path / "small.nc")
    assert seen and all(size == writer.READBACK_CACHE == 2 ** 20 for size in seen)
    assert netCDF4.get_chunk_cache() == default


def test_a_rough_surface_is_one_period_on_a_periodic_grid(tmp_path):
    """32^2 periodic cell, a rough surface (H = 0.8, rms height 0.2 um), W = 100 N: the
    contact laws hold, and the same surface shifted by (7, 12) cells (its gap as a .npy
    file) gives the pressure shifted by as much (to 1e-6 of its largest value): the
    generated surface and the contact have no edge."""
    side = 3 * A_HERTZ
    geo = {"shape": "rough", "hurst": 0.8, "rms_height": 2e-7,
           "wavelengths": [side / 2, 4 * side / 32], "seed": 2}
    grid = {"points": [32, 32], "size": [side, side], "boundary": "periodic"}
    load = {"time": [0.0, 1.0], "normal_force": 100.0}
    ds = cp.simulate(make_scene(geometry=geo, grid=grid, load=load))
    assert contact_law_violations(ds) == []
    path = tmp_path / "shifted.npy"
    np.save(path, np.roll(ds["h0"].values, (7, 12), axis=(0, 1)))
    moved = cp.simulate(make_scene(geometry={"shape": "surface", "file": str(path)},
                                   grid=grid, load=load))
    p, q = ds.p.values[-1], moved.p.values[-1]
    assert np.max(np.abs(np.roll(p, (7, 12), axis=(0, 1)) - q)) <= 1e-6 * p.max()


def test_clusters_join_across_a_periodic_grids_edges():
    """On one period of a surface, a patch cut by the grid's edges is one cluster: a
    band through the last and first columns, a corner patch in all four corners, and a
    cell at the top edge with none facing it across. The same map on a free grid counts
    each piece: 2 + 4 + 1."""
    s = np.full((10, 12), STATUS_SEPARATED, dtype=np.int8)
    s[3:6, -1] = STATUS_SLIP
    s[4:7, 0] = STATUS_SLIP                               # faces the band's rows 4, 5
    for i, j in ((0, 5), (0, 6), (-1, 5)):                # wraps over the x1 edge only
        s[i, j] = STATUS_STICK
    for i, j in ((0, 0), (0, -1), (-1, 0), (-1, -1)):     # the four corners: one patch
        s[i, j] = STATUS_STICK
    s[5, 8] = STATUS_STICK                                # inside, alone
    contact = s != STATUS_SEPARATED
    assert count_clusters(contact) == 2 + 1 + 4 + 1 + 1
    assert count_clusters(contact, periodic=True) == 1 + 1 + 1 + 1
    scene = 'name = "cell"\n[grid]\nboundary = "periodic"\n'
    ds = xr.Dataset({"status": (("time", "x1", "x2"), s[None])}, coords={"time": [0.0]},
                    attrs={"scene": scene})
    counts = contact_clusters(ds)
    assert int(counts.contact_clusters[0]) == 4
    assert int(counts.stick_clusters[0]) == 3
    assert int(counts.slip_clusters[0]) == 1
    ds.attrs["scene"] = scene.replace("periodic", "free")
    assert int(contact_clusters(ds).contact_clusters[0]) == 9
