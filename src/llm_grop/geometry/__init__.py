"""Geometry the planner and the simulators both need: the room's obstacles as the robot's
base sees them, and the time it takes to drive a path. It sits below both, so neither
imports the other."""
