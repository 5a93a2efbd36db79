"""Creep functions fitted to measured data (materials.fit_*): exact on data a Prony series
on the fitted grid represents, the relaxation -> creep interconversion against closed
forms (Zener, Maxwell), the fit error reported, bad data refused."""
import numpy as np
import pytest

from contactpipe.materials import (PronyFit, fit_creep_compliance, fit_dynamic_moduli,
                                   fit_relaxation_modulus, kelvin_voigt, prony, zener)
from contactpipe.solver.memory import error_amplification

T = np.concatenate([[0.0], np.logspace(-2, 2, 60)])         # 0 and 10 ms .. 100 s


def test_creep_table_of_a_prony_series():
    """A compliance table sampled from a 3-term Prony series whose retardation times lie on
    the fit's grid (2 per decade over 0.01-100 s): phi and E0 back to 1e-6 (measured
    3e-8), the reported error is the misfit (5e-9 rms), the fit's phi is stable under "bdf2"."""
    true = prony([[0.5, 0.1], [1.0, 1.0], [2.0, 10.0]])
    fit = fit_creep_compliance(T, true(T) / 2e9)
    assert isinstance(fit, PronyFit) and fit.source == "creep"
    assert fit.young == pytest.approx(2e9, rel=1e-6)
    tt = np.linspace(0.0, 300.0, 301)
    np.testing.assert_allclose(fit.creep(tt), true(tt), rtol=1e-6)
    assert fit.rms_error < 1e-6 and fit.max_error < 1e-6
    assert np.all(np.abs(error_amplification(fit.creep, 0.05, "bdf2")) <= 1.0)


def test_creep_table_without_instantaneous_compliance():
    """Kelvin-Voigt data (D(0) = 0): phi normalised by the long-term modulus, phi(0) = 0."""
    fit = fit_creep_compliance(T, kelvin_voigt(1.0)(T) / 1e9 + 0.0)
    assert fit.creep.phi0 == pytest.approx(0.0, abs=1e-12)
    assert fit.young == pytest.approx(1e9, rel=1e-6)
    np.testing.assert_allclose(fit.creep(T[1:]), kelvin_voigt(1.0)(T[1:]), rtol=1e-6)


def test_creep_table_with_a_dashpot():
    """Burgers data (one Kelvin element and a dashpot t' = 5 s): dashpot=True recovers b."""
    true = prony([[1.0, 1.0]], 5.0)
    fit = fit_creep_compliance(T, true(T) / 1e9, dashpot=True)
    assert fit.creep.b == pytest.approx(0.2, rel=1e-6)
    np.testing.assert_allclose(fit.creep(T), true(T), rtol=1e-6)


def test_power_law_creep_fit_error():
    """A broad spectrum the series does not contain (D = D0 (1 + t^0.3), 4 decades): the fit
    error is reported: 0.47 % rms, 2.3 % at most (2 terms per decade), at 0.59 % / 2.5 %
    with 1; phi positive and non-decreasing."""
    d = 1e-9 * (1.0 + T ** 0.3)
    two = fit_creep_compliance(T, d)
    one = fit_creep_compliance(T, d, terms_per_decade=1)
    assert two.rms_error < 0.006 and two.max_error < 0.025
    assert one.rms_error < 0.007 and one.max_error < 0.03
    assert np.all(np.diff(two.creep(np.logspace(-4, 4, 200))) >= 0)


def test_relaxation_table_converts_to_zener_creep():
    """E(t) = Einf + (E0 - Einf) exp(-t/tau_R), tau_R = 1 s on the grid: the creep function
    is Zener's with retardation time tau_R E0/Einf (closed-form interconversion), 1e-6."""
    e0, e_inf = 3e9, 1e9
    fit = fit_relaxation_modulus(T, e_inf + (e0 - e_inf) * np.exp(-T / 1.0))
    assert fit.young == pytest.approx(e0, rel=1e-6)
    tt = np.linspace(0.0, 30.0, 61)
    np.testing.assert_allclose(fit.creep(tt), zener(e0, e_inf, 3.0)(tt), rtol=1e-6)


def test_relaxation_table_of_a_maxwell_fluid():
    """E(t) = E0 exp(-t/tau): no long-term modulus, so the creep function has a dashpot,
    phi = 1 + t/tau (exactly the materials.maxwell form)."""
    fit = fit_relaxation_modulus(T, 3e9 * np.exp(-T / 1.0))
    assert fit.creep.b == pytest.approx(1.0, rel=1e-6)
    assert fit.creep.a == pytest.approx(1.0, rel=1e-6)
    np.testing.assert_allclose(fit.creep(T), 1.0 + T, rtol=1e-6)


def test_dynamic_moduli_convert_to_the_same_creep():
    """Storage and loss moduli of a two-term generalised Maxwell model (tau on the grid of
    2 per decade over 1/(2 pi f)): the creep function equals the one fitted from its
    relaxation table (both are exact interconversions), 1e-6."""
    f = np.logspace(-3, 2, 41)
    w = 2 * np.pi * f
    e_inf, terms = 1e9, [(2e9, 1 / (2 * np.pi)), (1e9, 10 / (2 * np.pi))]
    storage = e_inf + sum(e * (w * t) ** 2 / (1 + (w * t) ** 2) for e, t in terms)
    loss = sum(e * w * t / (1 + (w * t) ** 2) for e, t in terms)
    dyn = fit_dynamic_moduli(f, storage, loss)
    assert dyn.rms_error < 1e-6
    relax = fit_relaxation_modulus(T, e_inf + sum(e * np.exp(-T / t) for e, t in terms),
                                   times=[t for _, t in terms])
    assert dyn.young == pytest.approx(4e9, rel=1e-6)
    tt = np.linspace(0.0, 50.0, 51)
    np.testing.assert_allclose(dyn.creep(tt), relax.creep(tt), rtol=1e-6)


@pytest.mark.parametrize("call,match", [
    (lambda: fit_creep_compliance(T, -np.ones_like(T)), "must be finite and > 0"),
    (lambda: fit_creep_compliance(T, np.where(T > 1, 0.9, 1.0) * 1e-9), "must not decrease"),
    (lambda: fit_relaxation_modulus(T, np.where(T > 1, 1.1, 1.0) * 1e9), "must not increase"),
    (lambda: fit_creep_compliance(T[::-1], np.ones_like(T)), "strictly ascending"),
    (lambda: fit_creep_compliance([0.0, 1.0], [1e-9, 2e-9]), "at least 3 points"),
    (lambda: fit_creep_compliance(T, np.full(T.size, np.nan)), "finite"),
    (lambda: fit_dynamic_moduli(np.logspace(-1, 1, 5), [5, 4, 3, 2, 1],
                                np.ones(5)), "storage modulus must not decrease"),
    (lambda: fit_creep_compliance(T, 1e-9 + T * 0, terms_per_decade=0), "terms_per_decade"),
    (lambda: fit_creep_compliance(T, 1e-9 + T * 0, times=[1.0, -1.0]), "times must be"),
])
def test_bad_data_refused(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_noise_within_the_allowance_is_fitted():
    """0.5 % Gaussian noise (seeded) on a Zener creep table drops the data by up to 1.6 %
    below its running maximum: refused with the default allowance (1 %), fitted with
    noise = 0.03, phi non-decreasing, rms error of the noise's size (measured 0.43 %)."""
    rng = np.random.default_rng(0)
    d = zener(3e9, 1e9, 1.0)(T) / 3e9 * (1 + 0.005 * rng.standard_normal(T.size))
    with pytest.raises(ValueError, match="noise allowance"):
        fit_creep_compliance(T, d)
    fit = fit_creep_compliance(T, d, noise=0.03)
    assert fit.rms_error < 0.006
    assert np.all(np.diff(fit.creep(np.logspace(-3, 3, 100))) >= 0)
