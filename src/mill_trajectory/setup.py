from setuptools import find_packages, setup

package_name = 'mill_trajectory'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='mill developers',
    maintainer_email='mill@example.com',
    description='Reference trajectories for the milling axes and the trajectory node.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'trajectory_node = mill_trajectory.executables:trajectory_node',
            'gcode-preview = mill_trajectory.executables:gcode_preview',
        ],
    },
)
