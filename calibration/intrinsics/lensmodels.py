"""Which mrcal lens model to solve for: names a user types, and the splined model's configuration.

``--lens-model`` accepts ``opencv8``, ``splined`` (a SPLINED_STEREOGRAPHIC sized for the imager and
the lens's field of view) or any full mrcal name (``LENSMODEL_OPENCV8``, ``LENSMODEL_SPLINED_STEREO
GRAPHIC_order=3_Nx=..``). The default for the Boson's 95 deg lens is OPENCV8: its 8 parameters cover
a 95 deg lens to a few hundredths of a pixel where there is data, stay well-behaved with 20-40
boards, and map one-to-one onto ROS ``rational_polynomial`` and OpenCV's rational model. A splined
model follows any lens exactly but needs boards in every part of the image, and no other tool reads it.
Without ``--lens-model`` the pipeline solves both OPENCV8 and OpenCV's Kannala-Brandt from the same
corners (and OPENCV5, which has no denominator and so no pole, in OPENCV8's place when OPENCV8 is
unusable), drops a model with a pole or fold inside the image (calibration/lens/health.py), and between
two healthy ones keeps the one that predicts held-out views better (calibration/intrinsics/model_choice.py:
Kannala-Brandt unless the mrcal model is significantly better; calibration/thermal/lens_choice.py).
The splined model is not a candidate of the default: on the bench's 40-image Kannala-Brandt "real"
set (36 boards) it was 17 px RMS off the truth over the image (Nx=20) and 11 px (Nx=12), its knots
outside the boards held only by regularisation.
"""
from __future__ import annotations

import math

DEFAULT = "opencv8"
SHORT_NAMES = ("opencv8", "splined")

# Knot grid of the splined model: the mrcal docs suggest ~30 x 20 for very wide lenses; a 95 deg
# lens on a 640 x 512 imager is well served by a grid with the imager's aspect ratio and fewer knots.
SPLINED_NX = 20


class LensModelError(ValueError):
    pass


def splined_name(imagersize: tuple[int, int], fov_x_deg: float, nx: int = SPLINED_NX) -> str:
    w, h = imagersize
    ny = max(4, int(round(nx * h / w)))
    return f"LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx={nx}_Ny={ny}_fov_x_deg={int(math.ceil(fov_x_deg))}"


def resolve(name: str | None, imagersize: tuple[int, int], fov_x_deg: float) -> str:
    """The full mrcal lens-model name for what the user asked (``None``: the default).
    ``fov_x_deg``: the horizontal field of view the splined model's knots must just cover."""
    import mrcal
    name = (name or DEFAULT).strip()
    low = name.lower()
    if low in ("opencv8", "lensmodel_opencv8"):
        return "LENSMODEL_OPENCV8"
    if low in ("splined", "splined_stereographic", "lensmodel_splined_stereographic"):
        return splined_name(imagersize, fov_x_deg)
    full = name if name.startswith("LENSMODEL_") else "LENSMODEL_" + name.upper()
    try:
        meta = mrcal.lensmodel_metadata_and_config(full)
        mrcal.lensmodel_num_params(full)
    except Exception:
        raise LensModelError(f"--lens-model {name!r}: not an mrcal lens model; use one of "
                             f"{', '.join(SHORT_NAMES)} or a full mrcal name such as LENSMODEL_OPENCV8") from None
    if not meta.get("has_core", 0) or full.startswith("LENSMODEL_CAHVORE"):
        raise LensModelError(f"--lens-model {name!r}: mrcal 2.2 cannot calibrate this model; use "
                             f"{' or '.join(SHORT_NAMES)}")
    return full


def is_splined(lensmodel: str) -> bool:
    return lensmodel.startswith("LENSMODEL_SPLINED")
