"""The keys of ``creep = "fit"`` that need the fit itself: the Young modulus it gives,
the options it takes, and the refusal of a fit whose creep compliance is off the data by
more than ``fit_tolerance`` (:data:`contactpipe.materials.FIT_TOLERANCE` by default).
"""
from __future__ import annotations

import math

from .. import materials
from .tables import Reader, show

__all__ = ["FIT_YOUNG_RTOL", "fit_options", "fitted_young"]

#: Relative difference of ``young`` from a fit's modulus that is refused (a stored scene
#: writes the fitted value back exactly; anything else is a contradiction).
FIT_YOUNG_RTOL = 1e-9


def fit_options(v: dict) -> dict:
    """The keyword options of materials.fit_table_file from a body's fit keys."""
    return {"terms_per_decade": v.get("terms_per_decade") or 2,
            "times": v.get("time_constants"), "free": v.get("free_times") is not False}


def fitted_young(r: Reader, v: dict):
    """The Young modulus of ``creep = "fit"`` [Pa]: from the fit (shear data with
    ``bulk = "elastic"``: 2 (1 + nu) G); a given ``young`` must agree. None (with the
    problem recorded, naming the file key) when the table is refused."""
    if v.get("terms_per_decade") is not None and v.get("time_constants") is not None:
        r.add(f"{r.key('time_constants')} and {r.key('terms_per_decade')} both give the "
              f"fit's time constants; give one")
        return None
    try:
        fit = materials.fit_table_file(v["file"], v["table_kind"], **fit_options(v))
    except ValueError as e:
        r.add(f"{r.key('file')} = {show(v['file'])} ({v['table_kind']} table): {e}")
        return None
    bound = v.get("fit_tolerance") or materials.FIT_TOLERANCE
    if not fit.compliance_error <= bound:
        r.add(f"{r.key('file')} = {show(v['file'])}: the fitted creep compliance is "
              f"{fit.compliance_error:.3g} off the {v['table_kind']} data, above "
              f"{r.key('fit_tolerance')} = {bound:g}; give more "
              f"{r.key('terms_per_decade')} (it took {len(fit.times)} time constants) or "
              f"raise {r.key('fit_tolerance')}")
        return None
    young = fit.young * (2.0 * (1.0 + v["poisson"]) if v.get("bulk") == "elastic" else 1.0)
    given = v.get("young")
    if given is not None and not math.isclose(given, young, rel_tol=FIT_YOUNG_RTOL):
        r.add(f"{r.key('young')} = {given:g} Pa contradicts the modulus of the fitted "
              f"table {young:.10g} Pa; leave young out (it is taken from the table)")
    return young
