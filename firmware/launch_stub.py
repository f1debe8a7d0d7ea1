"""Stand-ins for ROS 2's ``launch`` / ``launch_ros`` API, to import and run a generated launch file
on a machine without ROS (CI, a laptop) and see what it would start.

Each action records the arguments it was built with; :func:`load_launch_file` imports a launch file
with these modules in ``sys.modules`` (even where ROS is installed: nothing is started) and returns its
``generate_launch_description()``. The checks then read the recorded nodes and parameters.
"""
from __future__ import annotations

import importlib.util
import sys
import types
from contextlib import contextmanager
from pathlib import Path


class Recorded:
    """An action or substitution: its class name, positional and keyword arguments."""

    def __init__(self, *args, **kwargs):
        self.args = args
        self.kwargs = kwargs

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.args!r}, {self.kwargs!r})"


class LaunchDescription(Recorded):
    @property
    def entities(self) -> list:
        return list(self.args[0]) if self.args else []


class Node(Recorded):
    pass


class IncludeLaunchDescription(Recorded):
    pass


class PythonLaunchDescriptionSource(Recorded):
    pass


class ExecuteProcess(Recorded):
    pass


class DeclareLaunchArgument(Recorded):
    pass


class OpaqueFunction(Recorded):
    def run(self, launch_arguments: dict) -> list:
        return self.kwargs["function"](_Context(launch_arguments))


class _Context:
    def __init__(self, arguments: dict):
        self.launch_configurations = dict(arguments)


class LaunchConfiguration(Recorded):
    def perform(self, context: _Context) -> str:
        return context.launch_configurations[self.args[0]]


def _share_directory(package: str) -> str:
    return f"/opt/ros/share/{package}"


def _modules() -> dict[str, types.ModuleType]:
    def module(name: str, **attrs) -> types.ModuleType:
        m = types.ModuleType(name)
        m.__dict__.update(attrs)
        return m
    return {
        "launch": module("launch", LaunchDescription=LaunchDescription),
        "launch.actions": module("launch.actions", IncludeLaunchDescription=IncludeLaunchDescription,
                                 DeclareLaunchArgument=DeclareLaunchArgument, OpaqueFunction=OpaqueFunction,
                                 ExecuteProcess=ExecuteProcess),
        "launch.substitutions": module("launch.substitutions", LaunchConfiguration=LaunchConfiguration),
        "launch.launch_description_sources": module("launch.launch_description_sources",
                                                    PythonLaunchDescriptionSource=PythonLaunchDescriptionSource),
        "launch_ros": module("launch_ros"),
        "launch_ros.actions": module("launch_ros.actions", Node=Node),
        "ament_index_python": module("ament_index_python"),
        "ament_index_python.packages": module("ament_index_python.packages",
                                              get_package_share_directory=_share_directory),
    }


@contextmanager
def _stubbed():
    saved = {name: sys.modules.get(name) for name in _modules()}
    sys.modules.update(_modules())
    try:
        yield
    finally:
        for name, mod in saved.items():
            if mod is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = mod


def load_launch_file(path: Path) -> LaunchDescription:
    """Import a launch file (with the stand-ins) and return what generate_launch_description() built."""
    spec = importlib.util.spec_from_file_location(f"_launch_{path.stem.replace('.', '_')}", path)
    module = importlib.util.module_from_spec(spec)
    with _stubbed():
        spec.loader.exec_module(module)
        return module.generate_launch_description()
