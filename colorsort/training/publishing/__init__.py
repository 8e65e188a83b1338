"""What a finished pipeline run publishes: its Markdown tables and plots (``run_summary``), a shipped baseline with
its scores and README (``ship``), README's and the docs' tables from every shipped ``scores.json`` (``tables``), and
two runs side by side (``compare``)."""
