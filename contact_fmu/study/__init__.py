"""Parameter studies and other many-task work on dask.distributed.

``engine``: where tasks run (this process, a LocalCluster, a running cluster);
``sweep``: a scene's runs over varied values as rows (results.parquet); ``run``: one
case stepped through the FMU with its status; ``metrics``: summary values of a run;
``plot``: a metric over one or two varied names; ``tables``: creep-force tables built
through the engine. The runner knows no physics: what varies, what is measured and
how it is plotted is the scene's data ([sweep], ``scenario.schema``).
"""
