"""Code only the benchmark scripts (and their tests) use, kept out of the package: the tracking belt's cycle
bound (``cycle_bound``), one pick of a moving box (``seal_trial``), randomised sensor views with ground truth
(``sensor_views``) and an ACT checkpoint executing its chunks otherwise (``chunk_execution``). The scripts run
from ``benchmarks/`` import them as ``studies.<module>``; pytest finds them through ``pythonpath``."""
