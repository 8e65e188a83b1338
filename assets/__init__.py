"""MJCF models of the ColorSort cell, shipped inside the wheel as package data."""
