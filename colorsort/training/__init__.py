"""Learns: the learned baselines' recipes, their pipeline (demos, lerobot-train, colorsort-eval), reports, shipping."""
