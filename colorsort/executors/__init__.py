"""Where tasks run: local processes or a Ray cluster, behind one interface (``base.Executor``)."""
