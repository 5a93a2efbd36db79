"""The pipeline stages: sweeps on dask, comparison, figures, batch runs and the command line.

They read and write archives (:mod:`contactpipe.archive`); only the speed figures
(:mod:`~contactpipe.pipeline.cli.bench`) reach into the solver. One package per stage,
from the top down (imports flow down only: pyproject's import-linter contracts keep it so):

``cli/``      the ``contactpipe`` command (``main``: one sub-command per stage module),
              ``run`` (the batch pipeline: sweep -> compare -> plot, idempotent,
              cron-safe), ``compare`` (``contactpipe compare``: the table from the
              comparison, the figure from the figures), ``bench`` (speed figures),
              ``stress`` (``contactpipe stress`` and the pipeline's ``[stress]`` product)
``figures/``  ``plot`` (figures: functions take ``ax=``/``fig=`` and return the Figure;
              :func:`~contactpipe.pipeline.figures.plot.save_figure` writes them),
              ``stress`` (the panels of the ``stress`` figure), ``fretting`` (the
              ``fretting-map`` figure and the energy ratios), ``series`` (hysteresis,
              radii), ``sweeps`` (a sweep's variable over its members), ``regimes`` (the
              regime table of a fretting sweep), ``common`` (inputs opened one way, the
              closed form of an archive), ``canvas`` (:func:`new_figure`)
``sweep/``    ``driver`` (:func:`sweep`, resuming included, and ``contactpipe sweep``),
              ``combine`` (:func:`open_sweep`), ``execute`` (where the members run, who
              writes their archives), ``config`` (the sweep and pipeline files),
              ``manifest`` (``manifest.json``), ``members`` (the axes parsed into
              validated scenes), ``parameters`` (derived parameters: ``tau_ratio``,
              ``delta_amplitude``, ``delta_ratio``, :func:`register_parameter`)
``compare/``  ``tables`` (error tables against a closed form or a reference archive),
              ``output`` (the tables written and shown), ``reference`` (the closed forms
              a scene admits)
``inputs``    what the stages read from an archive: grid, scene, centre rows, radii

The modules' old paths (``contactpipe.pipeline.plot``, ``...run``, ``...members``, ...)
import until 0.2 with a DeprecationWarning.
"""
