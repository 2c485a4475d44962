from glob import glob

from setuptools import find_packages, setup

package_name = 'mill_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        # the RViz config and the Foxglove layout
        ('share/' + package_name + '/config', glob('config/*.rviz') + glob('config/*.json')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='mill developers',
    maintainer_email='mill@example.com',
    description='Scenario runner, launch file and offline simulator of mill.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'run_scenario = mill_bringup.executables:run_scenario',
            'offline_sim = mill_bringup.offline:main',
            'tune = mill_bringup.tuning.cli:main',
            'job_watch = mill_bringup.executables:job_watch',
            'job_server = mill_bringup.executables:job_server',
            'machine_view = mill_bringup.executables:machine_view',
            'mill_container = mill_bringup.executables:mill_container',
            'docs_figures = mill_bringup.docs_figures.cli:main',
            'docs_params = mill_bringup.docs_params:main',
        ],
    },
)
