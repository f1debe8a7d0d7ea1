"""A plain verdict on a calibration: can it be trusted, and if not, why (in words a user acts on).

Reprojection error alone says little (a model fitted to boards only in the centre has a tiny one);
the verdict rests on where the data is and on mrcal's projection uncertainty:

- every ninth of the image (corners, edges, centre) needs corners in it: a fisheye's corners are
  where its distortion is largest and where nothing else constrains the model;
- the projection uncertainty (worst direction, at infinity) must stay small over the central 80%
  and bounded over the whole image;
- the residuals must look like detection noise, and few images may have been rejected;
- cross-validation (validity.py): across the image, the solutions from two disjoint halves of the
  images must agree, corners must have been seen nearby and the uncertainty must be bounded.
  Where any fails, the model is "not trustworthy there", named ("the top-left corner has no data:
  the halves disagree by 3.1 px there"); more than MAX_UNTRUSTED_SHARE of the image so: not
  trustworthy at all. The trusted part is the valid-intrinsics region in the .cameramodel.
"""
from __future__ import annotations

from dataclasses import dataclass, field

MIN_CORNERS_PER_REGION = 20          # fewer corners in a ninth of the image: "little data"
MAX_UNCERTAINTY_CENTRAL_PX = 0.15    # over the central 80% of the image
MAX_UNCERTAINTY_PX = 0.5             # anywhere in the image
MAX_RMS_PX = 0.5                     # RMS reprojection error of inlier corners
MAX_REJECTED_IMAGE_FRACTION = 0.2
MAX_UNTRUSTED_SHARE = 0.01           # of the image (validity grid points) outside the trusted region


@dataclass
class Verdict:
    trustworthy: bool
    reasons: list[str] = field(default_factory=list)     # why not (empty if trustworthy)
    warnings: list[str] = field(default_factory=list)    # worth knowing, not disqualifying

    @property
    def headline(self) -> str:
        if self.trustworthy:
            return "trustworthy" + (f" ({'; '.join(self.warnings)})" if self.warnings else "")
        return "not trustworthy: " + "; ".join(self.reasons)

    def to_dict(self) -> dict:
        return dict(trustworthy=self.trustworthy, headline=self.headline, reasons=self.reasons,
                    warnings=self.warnings)


def judge(*, region_counts: dict[str, int], rms_px: float, n_images: int, n_rejected_images: int,
          uncertainty_central_px: float | None, uncertainty_max_px: float | None,
          validity=None, cross_validated: bool | None = None) -> Verdict:
    """``validity``: a report.validity.Validity (the trust map), which replaces the whole-image
    uncertainty limit with one per place; ``cross_validated`` False: there were too few images to
    cross-validate (itself a reason not to trust)."""
    v = Verdict(True)
    empty = [name for name, n in region_counts.items() if n == 0]
    sparse = [f"{name} ({n} corners)" for name, n in region_counts.items() if 0 < n < MIN_CORNERS_PER_REGION]
    for name in empty:
        v.reasons.append(f"the {name} has no data")
    if sparse:
        v.reasons.append("little data in the " + ", ".join(sparse))
    if empty or sparse:
        v.reasons.append("take more images with the board in those parts of the image")
    if uncertainty_central_px is None:
        v.warnings.append("no projection uncertainty (the OpenCV solver does not give one)")
    else:
        if uncertainty_central_px > MAX_UNCERTAINTY_CENTRAL_PX:
            v.reasons.append(f"projection uncertainty up to {uncertainty_central_px:.2f} px in the central "
                             f"80% of the image (limit {MAX_UNCERTAINTY_CENTRAL_PX} px)")
        if validity is None and uncertainty_max_px is not None and uncertainty_max_px > MAX_UNCERTAINTY_PX:
            v.reasons.append(f"projection uncertainty up to {uncertainty_max_px:.2f} px near the image "
                             f"edges (limit {MAX_UNCERTAINTY_PX} px)")
    if cross_validated is False:
        v.reasons.append(f"too few images ({n_images}) to cross-validate: take at least 8, with the board "
                         f"in every part of the image")
    if validity is not None and validity.regions:
        said = [r.sentence() for r in validity.regions]
        untrusted = 1.0 - validity.trusted_share
        if untrusted > MAX_UNTRUSTED_SHARE:
            v.reasons.extend(said[:4] + ([f"and {len(said) - 4} more part(s)"] if len(said) > 4 else []))
            v.reasons.append(f"the model can be trusted over {100 * validity.trusted_share:.0f}% of the image "
                             f"(the valid-intrinsics region written into the .cameramodel): take images with "
                             f"the board over the parts named")
        else:
            v.warnings.append("outside the valid-intrinsics region (" + f"{100 * untrusted:.1f}% of the image): "
                              + "; ".join(said))
    if rms_px > MAX_RMS_PX:
        v.reasons.append(f"RMS reprojection error {rms_px:.2f} px (limit {MAX_RMS_PX} px): corners are "
                         f"noisy or the lens model does not fit")
    total = n_images + n_rejected_images
    if total and n_rejected_images / total > MAX_REJECTED_IMAGE_FRACTION:
        v.reasons.append(f"{n_rejected_images} of {total} images rejected as outliers")
    elif n_rejected_images:
        v.warnings.append(f"{n_rejected_images} image(s) rejected as outliers")
    v.trustworthy = not v.reasons
    return v
