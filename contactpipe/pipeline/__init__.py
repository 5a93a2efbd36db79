"""The pipeline stages: sweeps on dask, comparison, figures, batch runs and the command line.

They read and write archives (:mod:`contactpipe.archive`) and never reach into the solver.
"""
