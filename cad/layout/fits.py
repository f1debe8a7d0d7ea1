"""The walls, clearances and hole fits every subsystem of the layout is built with (mm), all read
from the rig description (``enclosure``, ``printing``), and the case's heat-set insert."""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig

from cad.bought.fasteners import Insert, thread_diameter_mm


@dataclass(frozen=True)
class Fits:
    wall: float                 # the case wall (enclosure.wall_mm)
    clear: float                # between a part and anything around it (enclosure.component_clearance_mm)
    gap: float                  # around a heat sink (enclosure.heat_sink_gap_mm)
    min_wall: float             # the thinnest wall the printer makes: nozzle x min_wall_nozzles
    insert: Insert              # the heat-set insert every printed screw joint uses
    screw_holes_mm: dict[str, float]   # clearance hole per thread name at the configured screw fit
    sliding_mm: float           # printing.fits.sliding_mm: diametral play of a thread with no table entry

    @classmethod
    def from_rig(cls, rig: Rig) -> "Fits":
        d = rig.desc
        e, p = d.enclosure, d.printing.printer
        holes = {name: getattr(h, f"{e.screw_fit}_mm") for name, h in d.printing.holes.items()}
        return cls(wall=e.wall_mm, clear=e.component_clearance_mm, gap=e.heat_sink_gap_mm,
                   min_wall=p.nozzle_mm * p.min_wall_nozzles, insert=Insert.from_rig(rig, e.insert),
                   screw_holes_mm=holes, sliding_mm=d.printing.fits.sliding_mm)

    @property
    def insert_plate_mm(self) -> float:
        """The thinnest printed plate that holds an insert: its hole plus a wall under it."""
        return self.insert.hole_depth_mm + self.min_wall

    def screw_hole_mm(self, thread: str) -> float:
        """Clearance hole diameter of a printed part for ``thread`` ("M3", "1/4-20 UNC")."""
        name = thread.split()[0]
        if name in self.screw_holes_mm:
            return self.screw_holes_mm[name]
        return thread_diameter_mm(thread) + 2 * self.sliding_mm
