"""The console scripts: each parses its typed configuration, calls the layers below and prints what they did;
``colorsort-eval`` also keeps its run's journal beside ``--json`` (``benchmark/sweep_journal.py``)."""
