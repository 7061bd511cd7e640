"""Builders of parallel mechanisms: URDF legs written with yourdfpy, and designs."""

from .urdf_writer import JointSpec, chain_robot, chain_urdf, robot_to_xml

__all__ = ["JointSpec", "chain_robot", "chain_urdf", "robot_to_xml"]
