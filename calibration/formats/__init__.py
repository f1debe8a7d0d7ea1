"""Write a solved thermal lens in the formats other tools read: OpenCV FileStorage YAML, ROS
camera_info YAML and a Kalibr camchain entry. Each writer returns the file's text; where a format
cannot represent the lens exactly, :mod:`.conversions` fits the nearest model it can and the file
and the summary both say how far that fit is."""
from .conversions import Representation, exact_or_nearest, nearest_for_ros, nearest_kalibr, representation
from .kalibr import kalibr_camchain
from .opencv_yaml import opencv_yaml
from .ros_camera_info import ros_camera_info

__all__ = ["Representation", "representation", "exact_or_nearest", "nearest_for_ros", "nearest_kalibr",
           "opencv_yaml", "ros_camera_info", "kalibr_camchain"]
