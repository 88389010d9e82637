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
    install_requires=["setuptools", "numpy", "scipy", "networkx", "matplotlib", "numba"],
    zip_safe=True,
    maintainer="rpr3-gwr maintainers",
    maintainer_email="maintainers@rpr3-gwr.dev",
    description="Global workspace roadmap planning for the planar 3-RPR, without ROS.",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={"console_scripts": ["rpr3-gwr = rpr3_gwr_core.io.cli:main"]},
)
