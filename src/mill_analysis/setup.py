from setuptools import find_packages, setup

package_name = 'mill_analysis'

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
    description='Records of mill runs (from messages or bags), their metrics, the verdicts of the papers and the report of bags.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'report = mill_analysis.report.cli:main',
            'identify = mill_analysis.identify.cli:main',
        ],
    },
)
