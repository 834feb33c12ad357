"""Studies of many independent simulations, no ROS inside: the one-run path every command
shares (``single``) and the stick-slip map engine (grid points run in this process, on a local
process pool or on a Dask cluster, stored and resumed as CSV)."""

from .single import RunSettings, SingleRun, default_start, point_metrics, run_single

__all__ = ["RunSettings", "SingleRun", "default_start", "point_metrics", "run_single"]
