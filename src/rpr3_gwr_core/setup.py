from setuptools import find_packages, setup

package_name = "rpr3_gwr_core"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    # From a stock ROS 2 Jazzy's versions (Ubuntu 24.04's packages, the floor)
    # to the pins of ros2_ws/requirements.txt, both tested.
    python_requires=">=3.11",
    install_requires=["setuptools", "numpy>=1.26.4,<3", "scipy>=1.11.4,<2",
                      "networkx>=3.2.1,<4", "matplotlib>=3.6.3,<4", "PyYAML>=6.0.1,<7",
                      "numba>=0.59.1,<1"],
    zip_safe=True,
    maintainer="rpr3-gwr maintainers",
    maintainer_email="maintainers@rpr3-gwr.dev",
    description="Global workspace roadmap planning for the planar 3-RPR, without ROS.",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={"console_scripts": ["rpr3-gwr = rpr3_gwr_core.io.cli:main"]},
)
