"""Decides: the colour sensor (OpenCV), motion planning (mink, ruckig) and the scripted expert."""
