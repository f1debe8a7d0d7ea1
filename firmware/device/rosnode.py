"""Running one rclpy node as a process: the ``main()`` of every ROS 2 node of this package (ffc_node,
health_node). rclpy (device only) is imported when :func:`spin` runs, so this module imports anywhere."""
from __future__ import annotations

import sys
from typing import Callable


def spin(make_node: Callable[[], object], argv: list[str] | None = None) -> int:
    """Initialise rclpy with ``argv`` (the process's arguments by default: ``--ros-args ...``), spin the node
    ``make_node()`` builds until Ctrl-C or shutdown, then destroy it and shut rclpy down if it is still up;
    exit code 0. An exception other than Ctrl-C still destroys the node and goes on."""
    import rclpy
    rclpy.init(args=sys.argv if argv is None else argv)
    node = make_node()
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
