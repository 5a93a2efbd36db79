"""The normal Hertz solve side by side with Tamaas, in one process.

    python benchmarks/vs_tamaas.py [--grids 64 128 256 512] [--reps 3] [--tol 1e-10]
                                   [--threads 1] [--no-plain]

Problem: steel sphere R = 18 mm on steel (E = 210 GPa, ν = 0.3), W = 1 kN, a square grid
of N x N cells over 4a, non-periodic (DC-FFT, zero padding to 2N x 2N) in both codes.
Both start cold, from zero traction, at every repetition, and solve to a tolerance of
1e-10 (each code's own measure: contactpipe's relative change Σ|Δp| / Σp, Tamaas's
complementarity error).

- contactpipe: :func:`contactpipe.solver.normal.solve_normal` (preconditioned CG with the
  multilevel start; ``--no-plain`` leaves out the plain Polonsky-Keer CG, the solver of
  before, printed for comparison), on the kernel spectra of the grid (set-up, cached).
- Tamaas (optional extra ``bench``: ``pip install tamaas``): ``PolonskyKeerRey`` with the
  non-periodic ``dcfft`` operator (``ModelFactory.registerNonPeriodic`` *and*
  ``setIntegralOperator("dcfft")``; without the second it silently solves the periodic
  problem). Its ``dcfft`` operator behaves as a contact modulus of 2E² (Tamaas 2.8.1 and
  2.9.0; with E = E* the Hertz pressure is off by a factor of 10² to 10⁴), so the problem
  is posed in units of E*: model.E = 1/√2, ν = 0, pressures returned in E* and scaled
  back. Tamaas warm-starts from ``model.traction``: it is zeroed before each solve. The
  surface heights are taken at the cell centres of contactpipe's grid.

Set-up (FFT plans, kernel spectra, Tamaas's model and operator) is done once per grid and
left out of the times. The two solvers alternate, repetition by repetition, and the
minimum of each is kept, so that the load of a shared machine weighs on both alike; the
time ratio is contactpipe / Tamaas (below 1: contactpipe is faster). Errors are against
the Hertz closed form at the cell centres: the peak pressure, and the RMS of the pressure
difference over the grid, both relative to p0. Wall times on a shared machine are
indicative; the FFT pairs are exact.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

from contactpipe.analytic import hertz_sphere
from contactpipe.materials import Body
from contactpipe.scene.geometry import sphere_gap
from contactpipe.solver.normal import solve_normal
from contactpipe.solver.operator import ContactOperator, body_spectra, convolver

E, NU, R, W = 210e9, 0.3, 0.018, 1000.0
E_STAR = 1.0 / (2.0 * (1.0 - NU ** 2) / E)
HERTZ = hertz_sphere(W, R, E_STAR)
A, P0 = HERTZ.contact_radius, HERTZ.max_pressure


def grid(n):
    """(cell centres [m], cell side [m]) of the n x n grid over 4a."""
    d = 4.0 * A / n
    return (np.arange(n) + 0.5) * d - 2.0 * A, d


def errors(p, x):
    """(peak error, RMS error) of a pressure field against Hertz, relative to p0."""
    ref = HERTZ.pressure(np.hypot(x[:, None], x[None, :]))
    return p.max() / P0 - 1.0, float(np.sqrt(np.mean((p - ref) ** 2))) / P0


class Ours:
    """contactpipe's normal solve on one grid (plans and spectra made here, once)."""

    def __init__(self, n, tol, threads, fast=True):
        x, d = grid(n)
        steel = Body("elastic", E, NU)
        spectra = body_spectra(steel, n, n, d, d, "auto", threads)
        self.op = ContactOperator(spectra, spectra, 1.0, 1.0,
                                  convolver(n, n, "auto", threads))
        self.gap, self.cell, self.x, self.tol = sphere_gap(x, x, R), d * d, x, tol
        self.fast = fast
        self.result, self.pairs = None, 0.0
        self.solve()                              # warm-up: the coarse grids' plans too

    def solve(self):
        conv = self.op.conv
        before = conv.pairs
        self.result = solve_normal(self.op, self.gap, W, self.cell, np.zeros_like(self.gap),
                                   self.tol, 10000, precondition=self.fast,
                                   multilevel=self.fast)
        self.pairs = conv.pairs - before
        return self.result.p


class Theirs:
    """Tamaas's PolonskyKeerRey on the same grid, non-periodic, in units of E*."""

    def __init__(self, tm, n, tol):
        x, d = grid(n)
        size = n * d
        self.model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [size, size], [n, n])
        tm.ModelFactory.registerNonPeriodic(self.model, "dcfft")
        self.model.E, self.model.nu = 2.0 ** -0.5, 0.0     # dcfft: contact modulus 2E² = 1
        self.solver = tm.PolonskyKeerRey(self.model,
                                         np.ascontiguousarray(-sphere_gap(x, x, R)), tol)
        self.solver.setIntegralOperator("dcfft")
        self.solver.max_iter = 100000
        self.mean = W / (size * size) / E_STAR
        self.x = x

    def solve(self):
        self.model.traction[...] = 0.0               # cold: Tamaas starts from the traction
        self.solver.solve(self.mean)
        return np.array(self.model.traction).reshape(self.x.size, self.x.size) * E_STAR


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return time.perf_counter() - t0, out


def side_by_side(tm, n, reps, tol, threads, plain):
    ours = Ours(n, tol, threads)
    before = Ours(n, tol, threads, fast=False) if plain else None
    theirs = Theirs(tm, n, tol) if tm is not None else None
    best = {"ours": np.inf, "plain": np.inf, "tamaas": np.inf}
    fields = {}
    for _ in range(reps):                           # interleaved: load hits both alike
        for key, solver in (("ours", ours), ("tamaas", theirs), ("plain", before)):
            if solver is None:
                continue
            t, fields[key] = timed(solver.solve)
            best[key] = min(best[key], t)
    e_ours = errors(fields["ours"], ours.x)
    e_theirs = errors(fields["tamaas"], theirs.x) if theirs is not None else (np.nan,) * 2
    ratio = best["ours"] / best["tamaas"] if theirs is not None else np.nan
    plain_cols = ""
    if before is not None:
        plain_cols = (f" {before.result.iterations:>5} {before.pairs:>6.0f} "
                      f"{best['plain'] * 1e3:>8.1f} {best['plain'] / best['tamaas']:>6.3f}"
                      if theirs is not None else "")
    print(f"{n:>4}x{n:<4} {ours.result.iterations:>5} {ours.pairs:>6.1f} "
          f"{best['ours'] * 1e3:>8.1f} {best['tamaas'] * 1e3:>9.1f} {ratio:>6.3f} "
          f"{e_ours[0]:>+9.2e} {e_theirs[0]:>+9.2e} {e_ours[1]:>8.2e} {e_theirs[1]:>8.2e}"
          f"{plain_cols}", flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grids", type=int, nargs="+", default=[64, 128, 256, 512])
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--tol", type=float, default=1e-10)
    parser.add_argument("--threads", type=int, default=1, help="contactpipe's FFT threads")
    parser.add_argument("--no-plain", action="store_true",
                        help="leave out the plain Polonsky-Keer CG (the solver of before)")
    args = parser.parse_args(argv)
    try:
        import tamaas as tm  # optional: the 'bench' extra
        tm.set_log_level(tm.LogLevel.error)
        version = tm.__version__
    except ImportError as err:
        tm, version = None, f"not importable ({err}); pip install tamaas"
    print(f"Hertz, steel on steel, W = 1 kN, R = 18 mm, grid over 4a, tolerance {args.tol:g}, "
          f"cold starts, min of {args.reps} interleaved repetitions; Tamaas {version}")
    print(f"machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} (a shared "
          "machine: wall times and ratios indicative, FFT pairs exact)")
    head = (f"{'grid':>9} {'iter':>5} {'pairs':>6} {'ours ms':>8} {'Tamaas ms':>9} {'ratio':>6} "
            f"{'p0 err':>9} {'Tam. p0':>9} {'RMS err':>8} {'Tam. RMS':>8}")
    if not args.no_plain:
        head += f" {'PK it':>5} {'pairs':>6} {'PK ms':>8} {'ratio':>6}"
    print(head)
    for n in args.grids:
        side_by_side(tm, n, args.reps, args.tol, args.threads, not args.no_plain)
    return 0


if __name__ == "__main__":
    sys.exit(main())
