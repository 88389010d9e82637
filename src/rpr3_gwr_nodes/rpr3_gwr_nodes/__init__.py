"""ROS 2 nodes of the rpr3-gwr suite."""
