from setuptools import find_packages, setup

package_name = 'mill_common'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['fastdds_profile.xml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='mill developers',
    maintainer_email='mill@example.com',
    description='Shared ROS adapters for mill: topic names, QoS, stamps, parameter checking, node entry.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [],
    },
)
