"""Parameter studies: sweeps and ensembles over grids and samples, on Dask.

:func:`~nhham.study.sweep.sweep` evaluates a scene's stability (``linearize``), runs
(``simulate``) or constraint-set verdict (``classify``) at every point of a grid or of
samples (:mod:`~nhham.study.points`), in chunks run by Dask or in this process
(:mod:`~nhham.study.schedule`; :mod:`~nhham.study.tasks` is what a worker receives and
does), written as they finish to a labelled xarray Dataset on disk
(:mod:`~nhham.study.store`; what ``--out`` may replace or resume:
:mod:`~nhham.study.target`), so that an interrupted study resumes; the ``--budget`` and
Ctrl-C stop the chunks (:mod:`~nhham.study.stop`), and the lines of a linearize grid
longer than a chunk are computed in pieces (:mod:`~nhham.study.lines`). What each kind
computes: :mod:`~nhham.study.stability`, :mod:`~nhham.study.ensemble`,
:mod:`~nhham.study.classes`; pictures: :mod:`~nhham.study.plots`.

Needs the study extra (``pip install 'nhham[study]'``: dask.distributed, xarray, zarr).
"""
