"""firmware.device.rosnode.spin, the main() of every ROS 2 node here, against a stand-in rclpy module that records
what is called (rclpy itself is device only)."""
from __future__ import annotations

import sys
import types

import pytest

from firmware.device.rosnode import spin


class _Node:
    def __init__(self, calls: list) -> None:
        self.calls = calls

    def destroy_node(self) -> None:
        self.calls.append("destroy")


def _fake_rclpy(monkeypatch, spin_raises: type[BaseException] | None, ok_after: bool) -> list:
    calls: list = []
    mod = types.ModuleType("rclpy")

    def init(args):
        calls.append(("init", list(args)))

    def spin_(node):
        calls.append("spin")
        if spin_raises is not None:
            raise spin_raises()

    mod.init, mod.spin = init, spin_
    mod.ok = lambda: ok_after
    mod.shutdown = lambda: calls.append("shutdown")
    monkeypatch.setitem(sys.modules, "rclpy", mod)
    return calls


@pytest.mark.parametrize("ok_after", [True, False])
def test_ctrl_c_destroys_the_node_and_shuts_down_once(monkeypatch, ok_after):
    calls = _fake_rclpy(monkeypatch, KeyboardInterrupt, ok_after)
    assert spin(lambda: _Node(calls), ["node", "--ros-args", "-p", "x:=1"]) == 0
    expected = [("init", ["node", "--ros-args", "-p", "x:=1"]), "spin", "destroy"]
    assert calls == expected + (["shutdown"] if ok_after else [])   # rclpy already down (its own signal handler)


def test_an_error_in_the_node_still_destroys_it_and_goes_on(monkeypatch):
    calls = _fake_rclpy(monkeypatch, RuntimeError, True)
    with pytest.raises(RuntimeError):
        spin(lambda: _Node(calls), [])
    assert calls == [("init", []), "spin", "destroy", "shutdown"]


def test_the_process_arguments_by_default(monkeypatch):
    calls = _fake_rclpy(monkeypatch, None, True)
    monkeypatch.setattr(sys, "argv", ["python3", "--ros-args", "--params-file", "/config/health.yaml"])
    spin(lambda: _Node(calls))
    assert calls[0] == ("init", ["python3", "--ros-args", "--params-file", "/config/health.yaml"])
