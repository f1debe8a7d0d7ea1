"""When each camera of the simulated rig captured, and every timing fault injected.

One trigger at sync.rate_hz drives all four cameras. The ZED stamps its frames at the trigger edge
(plus a small jitter); the Bosons trigger on sync.edge: on the falling edge of the capture card's
quarter-period-wide pulse they capture a quarter period later. Each Boson also has a fixed
transport offset and its own jitter. Then: frames dropped at random, an FFC per Boson (status topic
says so, the image freezes for its duration), and one step of the host clock.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..rig import Rig

NS = 1_000_000_000
CAMERAS = ("zed_left", "zed_right", "thermal_left", "thermal_right")


@dataclass(frozen=True)
class SimParams:
    duration_s: float
    seed: int = 0
    drop_probability: float = 0.005
    zed_jitter_ms: float = 0.2
    thermal_jitter_ms: float = 0.6
    thermal_latency_ms: tuple[float, float] = (2.1, 2.7)    # left, right: USB transport
    ffc_duration_s: float = 0.5
    clock_step_ms: float = 250.0
    imu_hz: float = 200.0
    start_ns: int = 1_700_000_000 * NS
    #: the thermal stamps run fast by this much against the ZED's (0: one clock; sync-check's drift)
    thermal_drift_ppm: float = 0.0


@dataclass
class Frame:
    camera: str
    index: int            # trigger pulse number
    stamp_ns: int         # header stamp, as the driver wrote it (clock step included)
    frozen: bool = False  # an FFC is in progress: the image repeats the last one before it


@dataclass
class Timeline:
    params: SimParams
    rate_hz: float
    frames: list[Frame]
    imu_stamps_ns: list[int]
    ffc: list[dict]                 # camera, start_ns, end_ns (true times)
    dropped: dict[str, list[int]]
    offsets_ms: dict[str, float]
    clock_step: dict
    status_ns: list[int] = field(default_factory=list)

    def truth(self) -> dict:
        return {"rate_hz": self.rate_hz, "params": asdict(self.params), "offsets_ms": self.offsets_ms,
                "dropped": self.dropped, "ffc": self.ffc, "clock_step": self.clock_step,
                "frames": {c: sum(1 for f in self.frames if f.camera == c) for c in CAMERAS},
                "triggers": int(round(self.params.duration_s * self.rate_hz))}


def build(rig: Rig, p: SimParams) -> Timeline:
    rng = np.random.default_rng(p.seed)
    rate = rig.desc.sync.rate_hz
    period_ns = NS / rate
    n = int(round(p.duration_s * rate))
    edge_ms = 1000.0 / rate / 4 if rig.desc.sync.edge == "falling" else 0.0
    offsets = {"zed_left": 0.0, "zed_right": 0.0,
               "thermal_left": edge_ms + p.thermal_latency_ms[0], "thermal_right": edge_ms + p.thermal_latency_ms[1]}
    step_at = p.start_ns + int(0.6 * p.duration_s * NS)
    step_ns = int(p.clock_step_ms * 1e6)

    def host(t_ns: int) -> int:
        return t_ns + (step_ns if t_ns >= step_at else 0)

    ffc = []
    for i, cam in enumerate(("thermal_left", "thermal_right")):
        start = p.start_ns + int((0.25 + 0.15 * i) * p.duration_s * NS)
        ffc.append({"camera": cam, "start_ns": start, "end_ns": start + int(p.ffc_duration_s * NS)})
    frames, dropped = [], {c: [] for c in CAMERAS}
    for cam in CAMERAS:
        jitter = p.zed_jitter_ms if cam.startswith("zed") else p.thermal_jitter_ms
        for k in range(n):
            if rng.random() < p.drop_probability:
                dropped[cam].append(k)
                continue
            t = p.start_ns + int(k * period_ns + offsets[cam] * 1e6 + rng.normal(0, jitter) * 1e6)
            if cam.startswith("thermal"):
                t += int(k * period_ns * p.thermal_drift_ppm * 1e-6)
            frozen = any(e["camera"] == cam and e["start_ns"] <= t < e["end_ns"] for e in ffc)
            frames.append(Frame(cam, k, host(t), frozen))
    imu = [host(p.start_ns + int(i * NS / p.imu_hz)) for i in range(int(p.duration_s * p.imu_hz))]
    status = [host(p.start_ns + int(i * NS)) for i in range(int(p.duration_s) + 1)]
    status = sorted(set(status + [host(e[k]) for e in ffc for k in ("start_ns", "end_ns")]))
    return Timeline(p, rate, frames, imu, ffc, dropped, offsets,
                    {"true_ns": step_at, "step_ns": step_ns}, status)


def ffc_state(timeline: Timeline, camera: str, host_ns: int) -> int:
    """Boson FFC status at a host time: 2 in progress, 3 complete (after one), 0 none."""
    step = timeline.clock_step
    true_ns = host_ns - (step["step_ns"] if host_ns >= step["true_ns"] + step["step_ns"] else 0)
    state = 0
    for e in timeline.ffc:
        if e["camera"] == camera:
            if e["start_ns"] <= true_ns < e["end_ns"]:
                return 2
            if true_ns >= e["end_ns"]:
                state = 3
    return state
