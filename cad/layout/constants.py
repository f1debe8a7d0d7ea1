"""The design's own choices: what the rig description does not decide (mm unless named).

:class:`Constants` holds the choices a user may want to tune (printed by ``cad/build.py params``);
the module-level names below are the smaller choices several layout modules share. Everything else
(the parts' sizes, the walls, the clearances, the printer) comes from the rig description.
"""
from __future__ import annotations

from dataclasses import dataclass

#: the two Bosons: side name and the sign of its rig y (left is +y, REP-103)
SIDES = (("left", 1.0), ("right", -1.0))

#: a cutting tool starts this far before the surface it cuts (and a hole runs this much deeper), so
#: the cut is clean through coincident faces
HOLE_LEAD_MM = 0.01
#: a handle foot's pad on the case reaches this far beyond the foot on every side
PAD_MARGIN_MM = 2.0


@dataclass(frozen=True)
class Constants:
    """Choices of this design that the rig description does not make (mm unless named)."""
    heat_sink_base_mm: float = 5.0       # copper block under each sleeve; holds the tapped M3 holes
    tapped_engagement_min_mm: float = 3.0
    duct_length_mm: float = 12.0         # fan outlet to the heat sink's fin bank
    duct_wall_mm: float = 1.2
    fan_plate_mm: float = 4.0            # the plate the fan is screwed to
    orin_standoff_min_mm: float = 5.0
    orin_standoff_diameter_mm: float = 8.0
    mount_shelf_mm: float = 6.0          # ZED X shelf
    mount_leg_mm: float = 8.0            # ZED mount legs (either side of the screw head)
    lug_width_mm: float = 12.0           # case split lugs, along the wall
    lug_protrusion_mm: float = 10.0
    lid_lug_mm: float = 4.0
    handle_post_width_mm: float = 16.0
    handle_foot_mm: float = 6.0
    handle_flange_mm: float = 8.0        # 12 left the grip 88 mm clear: its pads ran into the split lugs beyond 129 mm
    fov_margin_deg: float = 2.0          # windows are cut this much wider than the field of view
    fov_length_mm: float = 400.0         # how far ahead the field-of-view frusta are checked
    battery_screw_engagement_mm: float = 5.0   # thread depth in the dock adapter (estimate)
    exploded_mm: float = 60.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not value > 0:
                raise ValueError(f"design constant {name} must be > 0, got {value}")
        if self.duct_wall_mm >= self.duct_length_mm:
            raise ValueError("duct_wall_mm must be thinner than the duct is long")


C = Constants()
