"""The pipeline stages: sweeps on dask, comparison, figures, batch runs and the command line.

They read and write archives (:mod:`contactpipe.archive`); only the speed figures
(:mod:`~contactpipe.pipeline.cli.bench`) reach into the solver. Modules, from the top down
(imports flow down only: pyproject's import-linter contract keeps it so):

``cli``          the ``contactpipe`` command: one sub-command per stage module below
``run``          the batch pipeline (sweep -> compare -> plot, idempotent, cron-safe)
``sweep``        :func:`sweep` (resuming included) and ``contactpipe sweep``;
                 re-exports the sweep stage's public names
``compare_cli``  ``contactpipe compare`` (the table from compare, the figure from plot)
``bench``        ``contactpipe bench``: speed figures
``stress_cmd``   ``contactpipe stress`` and the pipeline's ``[stress]`` product
``plot``         figures: functions take ``ax=``/``fig=`` and return the Figure;
                 :func:`~contactpipe.pipeline.figures.plot.save_figure` writes them; inputs
                 (an archive, a stress file, a sweep folder) opened one way
``plot_stress``  the panels of the ``stress`` figure (x1-x3 section, surface map)
``plot_fretting`` the ``fretting-map`` figure (regimes over delta* and mu or W) and the
                 energy ratios against delta*/delta_gs
``regimes``      the regime table of a fretting sweep (Fouvry's energy ratio per member)
``compare``      error tables against a closed form or a reference archive
``combine``      :func:`open_sweep`: a sweep folder as one Dataset
``execute``      where the members run, and who writes their archives
``reference``    the closed forms a scene admits (:class:`ClosedForm`, ...)
``manifest``     a sweep folder's ``manifest.json``, written and validated
``members``      a sweep's axes parsed into members, each a validated scene
``parameters``   derived sweep parameters (``tau_ratio``, ``delta_amplitude``,
                 ``delta_ratio``, :func:`register_parameter`)
``inputs``       what the stages read from an archive: grid, scene, centre rows, radii
``figures``      :func:`new_figure`, the figure drawn into when no axes are given
"""
