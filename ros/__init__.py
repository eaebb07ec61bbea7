"""The ROS 2 room: htn as a ROS 2 node (issue 36), installed by the ``ros``
extra (ROS 2 Jazzy's PyPI wheels). Nothing in the core imports it; it uses
the use cases (:mod:`htn.api`), never the command line. The interface
package ``htn_interfaces`` (``interfaces/``) is found or built once by
:mod:`.interfaces` (with :mod:`.colcon`), which import no rclpy: what is
rclpy-specific stays in one module."""
