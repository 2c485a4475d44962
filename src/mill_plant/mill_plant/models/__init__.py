"""Per-axis dynamic models of the milling-machine plant (ROS-free), see base.AxisModel."""
