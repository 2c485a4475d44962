from setuptools import find_packages, setup

package_name = 'mill_bench'

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
    description='Benchmarks of mill: the lockstep job in each process layout, the realtime rates it holds, the empty-callback floor and an rclpy ping-pong.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'benchmark = mill_bench.benchmark:main',
        ],
    },
)
