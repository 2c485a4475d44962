"""Shared pieces of the mill suite: signal types and time base (ROS-free), and thin ROS helpers."""
