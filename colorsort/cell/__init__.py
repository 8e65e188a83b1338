"""The physics: the cell's parts (box pool, conveyor, referee, seal, cameras, lights), wired to one model in
``plant.py``; the robosuite task that hosts them is ``colorsort.envs.robosuite_task``."""
