"""The view of the robot: what it sees, how it stands and what it decides, drawn with Rerun."""
