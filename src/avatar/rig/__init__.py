"""Rigs: skeletons placed on the shaped mesh, kinematics and skinning."""
