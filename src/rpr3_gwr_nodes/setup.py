from glob import glob

from setuptools import setup

package_name = "rpr3_gwr_nodes"

setup(
    name=package_name,
    version="0.1.0",
    packages=[package_name],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/launch", glob("launch/*.launch.py")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="rpr3-gwr maintainers",
    maintainer_email="maintainers@rpr3-gwr.dev",
    description="ROS 2 nodes of the rpr3-gwr suite.",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "roadmap_builder = rpr3_gwr_nodes.roadmap_builder:main",
            "planner = rpr3_gwr_nodes.planner:main",
            "rpr3_driver = rpr3_gwr_nodes.rpr3_driver:main",
            "trajectory_recorder = rpr3_gwr_nodes.trajectory_recorder:main",
            "scene_publisher = rpr3_gwr_nodes.scene_publisher:main",
            "rpr3_gwr_recover_bag = rpr3_gwr_nodes.bag_recovery:main",
            "suite = rpr3_gwr_nodes.suite_launcher:main",
        ],
    },
)
