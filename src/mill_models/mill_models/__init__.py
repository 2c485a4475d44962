"""The model layer of mill: the mathematics every role package shares, ROS-free.

The role packages (mill_plant, mill_controllers, mill_observers, mill_trajectory) never
import one another; what more than one of them needs lives here. A plant simulates with
these models, a controller designs with them, an observer estimates with them.

Rules (checked by test/test_import_graph.py):

- numpy and scipy only: never rclpy or a ROS message package;
- of the mill packages, only mill_common's ROS-free modules (signals, parameters,
  declared, timebase);
- each equation of a paper sits in one module, with its one-line
  ``# Paper year eq. (n): ...`` comment.

Modules:

- axis_data: the rigid ball-screw axis of Beltrán 2013 (Table 1, m_e, c_e, b).
- identification: the rigid axis fitted to a record (b, friction, load, delay).
- frequency_response: an axis's response from its record, its resonances, a two-mass model.
- friction_id: breakaway and Stribeck friction from the record's stops.
- backlash_id: backlash from two encoders or from the table's alone.
- axis_model: which of these models a record supports, and why.
- force_process: Rubio 2013 eq. (1)-(3), the feed → peak-force process and its exact
  simulation under affine inputs.
- harmonics: the check of a list of harmonic multiples (the harmonic force and the DFO).
- holds: the β fractional-order hold of Rubio 2013 eq. (4)-(6) (input reconstruction,
  discretisation, a plant seen through the hold and a feed clamp) and the sample hold.
- polynomials: polynomials in z, the Sylvester matrix and the Diophantine equation.
- quadrature: Simpson's rule.
- reference_model: Rubio 2013 eq. (7), the reference model and its continuous response.
- rls: recursive least squares of Hatwesh 2013 eq. (10)-(13).
"""
