"""A plain verdict on a calibration: how far it can be trusted, and if not, why (in words a user acts on).

Reprojection error alone says little (a model fitted to boards only in the centre has a tiny one);
the verdict rests on where the data is and on mrcal's projection uncertainty:

- every ninth of the image (corners, edges, centre) needs corners in it: a fisheye's corners are
  where its distortion is largest and where nothing else constrains the model;
- the projection uncertainty (worst direction, at infinity) must stay small over the central 80%
  and bounded over the whole image;
- the residuals must look like detection noise, and few images may have been rejected;
- cross-validation (validity.py): across the image, the solutions from two disjoint halves of the
  images must agree, corners must have been seen nearby and the uncertainty must be bounded (and
  the halves must have differed at all: identical halves mean nothing was cross-validated).
  Where any fails, the model is "not trusted there", named ("the top-left corner has no data:
  the halves disagree by 3.1 px there"). The trusted part is the valid-intrinsics region in the
  .cameramodel.

Three grades (``Verdict.grade``, stable names for --json):

- ``trusted``: the whole image (at most MAX_UNTRUSTED_SHARE of it outside the trusted region, named
  in a warning, none of it in the central 80% beyond what trusted-within-region allows) and every
  ninth well covered;
- ``trusted-within-region``: usable inside its valid-intrinsics region, as mrcal users use a model:
  the central 80% of the image is trusted essentially everywhere (MIN_CENTRAL_TRUSTED_SHARE), at
  least MIN_TRUSTED_SHARE of the whole image is, and nothing else is wrong (RMS, rejected images,
  central uncertainty, cross-validation); the parts outside the region are named in the warnings;
- ``not-trusted``: anything else; the reasons say what to do.

``trustworthy`` (the first two) stays for compatibility.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

MIN_CORNERS_PER_REGION = 20          # fewer corners in a ninth of the image: "little data"
MAX_UNCERTAINTY_CENTRAL_PX = 0.15    # over the central 80% of the image
MAX_UNCERTAINTY_PX = 0.5             # anywhere in the image
MAX_RMS_PX = 0.5                     # RMS reprojection error of inlier corners
MAX_REJECTED_IMAGE_FRACTION = 0.2
MAX_UNTRUSTED_SHARE = 0.01           # of the image (validity grid points) outside the trusted region:
                                     # more, and the model is at best trusted within its region
# trusted-within-region: the central 80% of the image (calibration.lens.compare.central_mask, 480 of the
# 832 points of the 32 x 26 validity grid of a 640 x 512 imager) trusted at >= 99% of its points, i.e.
# all but a stray point or four: untrusted points in the middle of the image are a real fault (no
# boards there, halves disagreeing), not corners the boards missed.
MIN_CENTRAL_TRUSTED_SHARE = 0.99
# ... and at least 80% of the whole image trusted. The central 80% is only 64% of the image; the band
# around it (36%) is the wide field a fisheye is bought for, and where a lens fitted without data
# there goes wrong first. 0.8 asks for more than 40% of that band. On synthetic 40-board sets
# (tests/calibration/test_report.py's): boards that missed the image corners pass (the demo set 97%;
# no corner within 150 px of any of the four image corners: 86%, within 0.1 px of the true lens where
# trusted), boards kept inside the central 75-78% of the image do not (77-79% trusted, and 1.5-2.7 px
# off at trusted points at the edge of the data, where the trust map is least sure).
MIN_TRUSTED_SHARE = 0.8
# Two halves of noisy data never give the same lens: halves that agree within this everywhere did not
# move from the full solution they were seeded from (the half solves made no step), so
# cross-validation said nothing. Seen on a set with boards only in the central 82% of the image: the
# halves "agreed" within 1e-8 px while the model was 1.9 px off in the central 80%.
DEGENERATE_HALVES_DIFF_PX = 1e-6

TRUSTED = "trusted"
TRUSTED_WITHIN_REGION = "trusted-within-region"
NOT_TRUSTED = "not-trusted"
GRADES = (TRUSTED, TRUSTED_WITHIN_REGION, NOT_TRUSTED)


@dataclass
class Verdict:
    grade: str                                           # one of GRADES
    reasons: list[str] = field(default_factory=list)     # why not trusted (empty unless not-trusted)
    warnings: list[str] = field(default_factory=list)    # worth knowing, not disqualifying (for
                                                         # trusted-within-region: the parts outside it)
    trusted_share: float | None = None                   # of the image; None without a trust map
    limits: list[str] = field(default_factory=list)      # short: what keeps it within its region

    @property
    def trustworthy(self) -> bool:
        return self.grade in (TRUSTED, TRUSTED_WITHIN_REGION)

    @property
    def headline(self) -> str:
        if self.grade == TRUSTED:
            return "trusted over the whole image" + (f" ({'; '.join(self.warnings)})" if self.warnings else "")
        if self.grade == TRUSTED_WITHIN_REGION:
            share = "" if self.trusted_share is None else f" ({100 * self.trusted_share:.0f}% of the image)"
            return (f"trusted within its valid region{share}: {_listed(self.limits)}; take images with the "
                    f"board there to extend it")
        return "not trusted: " + "; ".join(self.reasons)

    def to_dict(self) -> dict:
        return dict(grade=self.grade, trustworthy=self.trustworthy, trusted_share=self.trusted_share,
                    headline=self.headline, reasons=self.reasons, warnings=self.warnings)


def _listed(parts: list[str], n: int = 2) -> str:
    """"a", "a and b", "a, b and 3 more part(s)"."""
    if not parts:
        return "parts of the image are not covered"
    if len(parts) <= n:
        return ", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else "".join(parts)
    return ", ".join(parts[:n]) + f" and {len(parts) - n} more part(s)"


def judge(*, region_counts: dict[str, int], rms_px: float, n_images: int, n_rejected_images: int,
          uncertainty_central_px: float | None, uncertainty_max_px: float | None,
          validity=None, cross_validated: bool | None = None, lens_problems: list[str] | None = None,
          cross_validation_error: str | None = None) -> Verdict:
    """``validity``: a report.validity.Validity (the trust map), which replaces the whole-image
    uncertainty limit with one per place and makes ``trusted-within-region`` possible (without it a
    model is trusted over the whole image or not at all); ``cross_validated`` False: there were too
    few images to cross-validate (itself a reason not to trust); ``lens_problems``: one line per exported
    model with a pole or fold inside the image or that does not round-trip (thermal/lens_check.py), each
    disqualifying; ``cross_validation_error``: the cross-validation could not run on this data (why)."""
    bad: list[str] = []          # disqualifying
    limit: list[str] = []        # not the whole image (with a trust map: trusted within its region)
    short: list[str] = []        # the same, briefly, for the headline
    warnings: list[str] = []
    said: list[str] = []         # the order the reasons are told in, when not trusted

    def add(text: str, disqualifying: bool) -> None:
        (bad if disqualifying else limit).append(text)
        said.append(text)

    # coverage by ninths; with a trust map it is that map which says whether the middle is usable
    empty = [name for name, n in region_counts.items() if n == 0]
    sparse = [f"{name} ({n} corners)" for name, n in region_counts.items() if 0 < n < MIN_CORNERS_PER_REGION]
    for name in empty:
        add(f"the {name} has no data", validity is None)
    if sparse:
        add("little data in the " + ", ".join(sparse), validity is None)
    if empty or sparse:
        add("take more images with the board in those parts of the image", validity is None)
    if uncertainty_central_px is None:
        warnings.append("no projection uncertainty (the OpenCV solver does not give one)")
    else:
        if uncertainty_central_px > MAX_UNCERTAINTY_CENTRAL_PX:
            add(f"projection uncertainty up to {uncertainty_central_px:.2f} px in the central "
                f"80% of the image (limit {MAX_UNCERTAINTY_CENTRAL_PX} px)", True)
        if validity is None and uncertainty_max_px is not None and uncertainty_max_px > MAX_UNCERTAINTY_PX:
            add(f"projection uncertainty up to {uncertainty_max_px:.2f} px near the image "
                f"edges (limit {MAX_UNCERTAINTY_PX} px)", True)
    for text in lens_problems or []:
        add(text, True)
    if cross_validation_error:
        add(f"cross-validation failed: {cross_validation_error}; nothing says where the model holds: take "
            f"more images, with the board in every part of the image", True)
    if cross_validated is False:
        add(f"too few images ({n_images}) to cross-validate: take at least 8, with the board "
            f"in every part of the image", True)
    halves = np.zeros(0) if validity is None or validity.halves_diff_px is None else \
        np.asarray(validity.halves_diff_px, dtype=float)
    halves = halves[np.isfinite(halves)]
    if halves.size and halves.max() < DEGENERATE_HALVES_DIFF_PX:
        add("cross-validation failed: the two halves' solutions are identical, i.e. neither moved from the "
            "full solve, so nothing says where the model holds; take more images, with the board in every "
            "part of the image", True)
    share = None
    if validity is not None:
        share = validity.trusted_share
        central = validity.central_trusted_share
        untrusted = 1.0 - share
        parts = [r.sentence() for r in validity.regions]
        parts = parts[:4] + ([f"and {len(parts) - 4} more part(s)"] if len(parts) > 4 else [])
        central_ok = central >= MIN_CENTRAL_TRUSTED_SHARE
        share_ok = share >= MIN_TRUSTED_SHARE
        if untrusted > MAX_UNTRUSTED_SHARE or not central_ok:
            usable = central_ok and share_ok
            for p in parts:
                add(p, not usable)
            short.extend(r.short() for r in validity.regions)
            if not central_ok:
                add(f"only {100 * central:.1f}% of the central 80% of the image is trusted (at least "
                    f"{100 * MIN_CENTRAL_TRUSTED_SHARE:.0f}% needed)", True)
            where = "the valid-intrinsics region written into the .cameramodel"
            if share_ok:
                said_share = f"the model can be trusted over {100 * share:.0f}% of the image ({where})"
            else:
                said_share = (f"the model can be trusted over only {100 * share:.1f}% of the image ({where}; at "
                              f"least {100 * MIN_TRUSTED_SHARE:.0f}% needed to use it within that region)")
            add(said_share + ("" if usable else ": take images with the board over the parts named"), not usable)
        elif validity.regions:
            warnings.append("outside the valid-intrinsics region (" + f"{100 * untrusted:.1f}% of the image): "
                            + "; ".join(parts))
    if not short:       # limited by the ninths' coverage alone
        short = [f"the {name} has no data" for name in empty] + (["little data in the " + ", ".join(sparse)]
                                                                 if sparse else [])
    if rms_px > MAX_RMS_PX:
        add(f"RMS reprojection error {rms_px:.2f} px (limit {MAX_RMS_PX} px): corners are "
            f"noisy or the lens model does not fit", True)
    total = n_images + n_rejected_images
    if total and n_rejected_images / total > MAX_REJECTED_IMAGE_FRACTION:
        add(f"{n_rejected_images} of {total} images rejected as outliers", True)
    elif n_rejected_images:
        warnings.append(f"{n_rejected_images} image(s) rejected as outliers")
    if bad:
        return Verdict(NOT_TRUSTED, reasons=said, warnings=warnings, trusted_share=share)
    if limit:
        return Verdict(TRUSTED_WITHIN_REGION, warnings=limit + warnings, trusted_share=share, limits=short)
    return Verdict(TRUSTED, warnings=warnings, trusted_share=share)
