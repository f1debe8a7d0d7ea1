"""Fault injection rules for the emulated Boson.

A rule is ``KIND[:SELECTOR...]``; several rules are separated by commas or given as repeated
``--faults``. Selectors: ``p=0.2`` (probability per request), ``n=3`` (only the 3rd request, counting
from 1), ``fid=0x00050098`` (only this function id), ``times=2`` (at most twice). Without selectors a
rule applies to every request. Kinds:

- ``drop``      drop a byte from the middle of the reply
- ``split``     send the reply in several pieces with short gaps
- ``badcrc``    corrupt the reply's CRC
- ``wrongseq``  first send a reply with a stale sequence number, then the right one
- ``garbage``   send random bytes before the reply
- ``stall``     do not answer at all (the command is not executed)
- ``busy``      answer FLR_CAM_BUSY (0x283) without executing
- ``notready``  answer FLR_NOT_READY (0x202) without executing
- ``reboot``    reboot in the middle of the command: no reply, the command is lost, the port vanishes
- ``ignore``    answer success without executing (a setting that does not stick: only a read-back sees it)
- ``delay``     answer ``s`` seconds late (default 1.5; a slow camera: it serves nothing else meanwhile)
"""
from __future__ import annotations

import random
from dataclasses import dataclass

KINDS = ("drop", "split", "badcrc", "wrongseq", "garbage", "stall", "busy", "notready", "reboot", "ignore", "delay")


@dataclass
class FaultRule:
    kind: str
    p: float | None = None
    n: int | None = None
    fid: int | None = None
    times: int | None = None     # remaining applications (None = unlimited)
    s: float | None = None       # seconds, for delay

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown fault {self.kind!r}; known: {', '.join(KINDS)}")
        if self.p is not None and not 0.0 <= self.p <= 1.0:
            raise ValueError(f"fault {self.kind}: p={self.p} is not a probability in [0, 1]")
        if self.n is not None and self.n < 1:
            raise ValueError(f"fault {self.kind}: n counts requests from 1")
        if self.times is not None and self.times < 0:
            raise ValueError(f"fault {self.kind}: times must be >= 0")
        if self.s is not None and not 0.0 <= self.s <= 60.0:
            raise ValueError(f"fault {self.kind}: s={self.s} is not a delay in seconds in [0, 60]")

    def fires(self, request_index: int, function_id: int, rng: random.Random) -> bool:
        """Whether this rule applies to this request; consumes one of ``times`` if it does."""
        if self.times == 0:
            return False
        if self.n is not None and request_index != self.n:
            return False
        if self.fid is not None and function_id != self.fid:
            return False
        if self.p is not None and rng.random() >= self.p:
            return False
        if self.times is not None:
            self.times -= 1
        return True

    def spec(self) -> str:
        parts = [self.kind] + [f"{k}={v if k != 'fid' else f'0x{v:08X}'}" for k, v in
                               (("p", self.p), ("n", self.n), ("fid", self.fid), ("times", self.times),
                                ("s", self.s))
                               if v is not None]
        return ":".join(parts)


def parse_rule(text: str) -> FaultRule:
    kind, *selectors = text.strip().split(":")
    kw: dict = {}
    for sel in selectors:
        key, sep, value = sel.partition("=")
        if not sep:
            raise ValueError(f"fault {text!r}: selector {sel!r} is not KEY=VALUE")
        try:
            if key in ("p", "s"):
                kw[key] = float(value)
            elif key in ("n", "times"):
                kw[key] = int(value)
            elif key == "fid":
                kw["fid"] = int(value, 0)
            else:
                raise ValueError(f"fault {text!r}: unknown selector {key!r} (p, n, fid, times, s)")
        except ValueError as exc:
            if "selector" in str(exc):
                raise
            raise ValueError(f"fault {text!r}: {key}={value!r} is not a number") from None
    return FaultRule(kind.strip(), **kw)


def parse_faults(texts) -> list[FaultRule]:
    """Rules from strings such as ``"busy:times=2,badcrc:p=0.1"`` (one or several strings)."""
    if isinstance(texts, str):
        texts = [texts]
    return [parse_rule(t) for text in texts for t in text.split(",") if t.strip()]
