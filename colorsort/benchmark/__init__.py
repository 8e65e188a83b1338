"""Evaluates: policies, episodes by seed on an executor (one env at a time, or cells stepped together with one
batched forward), held-out sweeps and their journal, metrics, films and the report page. The envs themselves are
in ``colorsort.envs``."""
