"""rpr3_gwr_core: global workspace roadmap planning for the planar 3-RPR, without ROS."""
