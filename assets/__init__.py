"""What ships inside the wheel as package data: the MJCF models of the ColorSort cell, the colour sensor's taught
classes (sensor/) and the learned baselines' model card (templates/)."""
