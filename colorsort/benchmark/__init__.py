"""Evaluates: the Gymnasium env, the LeRobot env config, policies, the harness and its metrics."""
