"""Studies of many independent simulations, no ROS inside: the one-run path every command
shares (``single``) and the stick-slip map engine: points run in this process, on a local process
pool or on a Dask cluster (``parallel``), their rows (``table``), stored and resumed as CSV with a
JSON description (``store``), the linear theory's lines (``theory``) and the figure (``figure``).
"""

from .parallel import ClusterError, available_cores, compute
from .single import RunSettings, SingleRun, default_start, point_metrics, run_single
from .store import MapStore, StoreError
from .table import METRICS, metric_row
from .theory import axial_neutral_speed, axial_threshold

__all__ = ["METRICS", "ClusterError", "MapStore", "RunSettings", "SingleRun", "StoreError",
           "available_cores", "axial_neutral_speed", "axial_threshold", "compute",
           "default_start", "metric_row", "point_metrics", "run_single"]
