"""The physics: the robosuite task and the cell's parts (box pool, conveyor, referee, seal, cameras, lights)."""
