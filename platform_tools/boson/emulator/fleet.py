"""Several emulated Bosons at once, as `platform_tools boson-emulator` serves them: one per serial
number, each on its own pseudo-terminal with its by-id link in one folder, all wired to one trigger,
sharing one session log.

    with Fleet([93588, 93589], trigger=Trigger(30.0)) as fleet:
        ...  # point discovery at fleet.by_id_dir; fleet.devices lists serial, pty and link
"""
from __future__ import annotations

import os
import shutil
import tempfile
import threading
from pathlib import Path
from typing import Mapping, Sequence, TextIO

from .. import commands as C
from ..discovery import BY_ID_ENV
from .device import EmulatedBoson
from .faults import FaultRule, parse_faults
from .state import BosonState
from .trigger import Trigger


class Fleet:
    """Emulated Bosons for ``serials``. ``by_id_dir``: where the by-id links go (default:
    $PLATFORM_TOOLS_BOSON_BY_ID, else a new temporary folder, removed on exit). Each camera gets its
    own copy of ``faults`` (and of ``faults_for[its serial]``, faults of that camera only) and the random
    seed ``seed + its index``; ``persist_slave`` starts them as if slave mode had been written to flash;
    ``boot_s`` is the simulated boot time in seconds."""

    def __init__(self, serials: Sequence[int], *, trigger: Trigger, by_id_dir: str | Path | None = None,
                 faults: Sequence[FaultRule] = (), seed: int = 0, boot_s: float = 0.5,
                 persist_slave: bool = False, log: TextIO | None = None,
                 faults_for: Mapping[int, Sequence[FaultRule]] | None = None):
        self.serials = list(serials)
        self.trigger = trigger
        self.faults = list(faults)
        self.faults_for = {sn: list(rules) for sn, rules in (faults_for or {}).items()}
        self.seed, self.boot_s, self.persist_slave, self.log = seed, boot_s, persist_slave, log
        self._temp_dir: str | None = None
        by_id = by_id_dir or os.environ.get(BY_ID_ENV)
        if not by_id:
            by_id = self._temp_dir = tempfile.mkdtemp(prefix="boson-by-id.")
        self.by_id_dir = str(by_id)
        self.cameras: list[EmulatedBoson] = []

    def start(self) -> "Fleet":
        lock = threading.Lock()
        for i, sn in enumerate(self.serials):
            state = BosonState(sn, trigger=self.trigger)
            if self.persist_slave:
                state.flash["ext_sync_mode"] = state.settings["ext_sync_mode"] = int(C.ExtSyncMode.SLAVE)
            self.cameras.append(EmulatedBoson(state, by_id_dir=self.by_id_dir,
                                              faults=[parse_faults(f.spec())[0] for f in
                                                      self.faults + self.faults_for.get(sn, [])],
                                              boot_s=self.boot_s, seed=self.seed + i, log=self.log,
                                              log_lock=lock).start())
        return self

    def stop(self) -> None:
        for camera in self.cameras:
            camera.stop()
        if self._temp_dir:
            shutil.rmtree(self._temp_dir, ignore_errors=True)

    def __enter__(self) -> "Fleet":
        try:
            return self.start()
        except BaseException:
            self.stop()
            raise

    def __exit__(self, *exc) -> None:
        self.stop()

    @property
    def devices(self) -> list[dict]:
        """One dict per camera: serial, path (its pty) and link (its by-id link)."""
        return [{"serial": e.serial, "path": e.path, "link": str(e.link)} for e in self.cameras]
