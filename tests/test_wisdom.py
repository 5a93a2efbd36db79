"""FFTW wisdom between processes (contactpipe.solver.wisdom): the file is written once a
grid is planned, taken back by a later process, ignored when foreign or unwritable, and
the plans it gives compute what freshly measured plans compute."""
import numpy as np
import pytest

from contactpipe.solver.convolution import HAVE_PYFFTW, Convolver

pytestmark = pytest.mark.skipif(not HAVE_PYFFTW, reason="wisdom is pyFFTW's")
wisdom = pytest.importorskip("contactpipe.solver.wisdom")


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """A process as if new: FFTW has forgotten its wisdom and the module has read no file;
    the wisdom file is tmp_path/w.txt."""
    import pyfftw

    def reset():
        pyfftw.forget_wisdom()
        monkeypatch.setattr(wisdom, "_known", {})

    reset()
    target = tmp_path / "w.txt"
    monkeypatch.setenv(wisdom.ENV, str(target))
    yield target, reset
    pyfftw.forget_wisdom()


def _field(n, seed=0):
    return np.random.default_rng(seed).random((n, n))


def _kernel(conv):
    k = np.zeros((conv.m1, conv.m2))
    k[0, 0], k[1, 0], k[0, 1], k[-1, 0], k[0, -1] = 4.0, 1.0, 1.0, 1.0, 1.0
    return conv.kernel_spectrum(k)


def test_wisdom_is_written_and_taken_back_by_a_later_process(fresh):
    target, reset = fresh
    conv = Convolver(16, 16)
    assert target.read_bytes().startswith(b"(fftw-")
    first = conv.convolve(_kernel(conv), _field(16))
    reset()
    # the file is read once and FFTW accepts it
    assert wisdom.load() is True
    assert wisdom.load() is False          # once per process
    again = Convolver(16, 16)
    # the same plans: the same rounding, bit for bit
    np.testing.assert_array_equal(again.convolve(_kernel(again), _field(16)), first)


def test_wisdom_turned_off_writes_nothing(monkeypatch, tmp_path):
    for value in ("off", "0", "none", ""):
        monkeypatch.setenv(wisdom.ENV, value)
        assert wisdom.path() is None
        Convolver(12, 12)
    assert list(tmp_path.iterdir()) == []


def test_foreign_wisdom_is_ignored_and_replaced(fresh):
    target, _ = fresh
    target.write_bytes(b"not (fftw wisdom")
    conv = Convolver(10, 10)
    x = _field(10, 1)
    k = np.zeros((20, 20))
    k[0, 0] = 2.0
    np.testing.assert_allclose(conv.convolve(conv.kernel_spectrum(k), x), 2.0 * x,
                               atol=1e-13)
    assert target.read_bytes().startswith(b"(fftw-")            # a valid file replaced it
    assert [p.name for p in target.parent.iterdir()] == ["w.txt"]   # no temporary left


def test_an_unwritable_wisdom_place_is_no_error(fresh, monkeypatch, tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    monkeypatch.setenv(wisdom.ENV, str(blocker / "w.txt"))      # its folder is a file
    conv = Convolver(8, 8)
    assert conv.convolve(_kernel(conv), _field(8)).shape == (8, 8)
    assert wisdom.save() is False


def test_default_place_is_the_user_cache(monkeypatch, tmp_path):
    import platform
    monkeypatch.delenv(wisdom.ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(platform, "node", lambda: "node 7/a")
    p = wisdom.path()
    assert p.parent == tmp_path / "contactpipe"
    assert p.name.startswith("fftw-wisdom-node_7_a-")          # one file per host
    # a relative XDG_CACHE_HOME is not valid (XDG): ~/.cache; no absolute home either:
    # none kept (not a folder named "~" in the working folder)
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert wisdom.path().parent == tmp_path / "home" / ".cache" / "contactpipe"
    monkeypatch.setenv("HOME", "not/absolute")
    assert wisdom.path() is None
