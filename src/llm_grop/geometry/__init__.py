"""Geometry the planner, the simulators, the executive and the rater share: the room's
obstacles as the robot's base sees them, the time it takes to drive a path, and an
object's footprint on the table. It sits below them all, so none imports another."""
