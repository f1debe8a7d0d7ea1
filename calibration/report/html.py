"""report.html: the summary, coverage, uncertainty, residuals and per-image errors of a solve, with
its verdict, as one self-contained page (inline SVG, inline CSS, nothing fetched)."""
from __future__ import annotations

import numpy as np
from jinja2 import Environment, PackageLoader, select_autoescape

from . import svg
from .analysis import Coverage, Uncertainty
from .verdict import Verdict


def plots(solution, coverage: Coverage, unc: Uncertainty | None, cv=None, val=None) -> dict[str, str]:
    obs = solution.observations
    size = solution.imagersize
    out = {
        "coverage": svg.heatmap(size, coverage.counts.astype(float),
                                vmax=max(float(coverage.counts.max()), 1.0), title="corners per cell",
                                unit="corners", label_cells=True, points=coverage.points),
        "scatter": svg.scatter(solution.residuals[solution.inlier], title="residuals of inlier corners",
                               rms=solution.rms_px),
        "per_image": svg.bars(obs.names, solution.per_image_rms_px, title="RMS residual per image", unit="px"),
    }
    outl = obs.seen() & ~solution.inlier
    res = np.where(solution.inlier[..., None], solution.residuals, np.nan)
    rms = max(solution.rms_px, 1e-3)
    out["arrows"] = svg.residual_arrows(size, obs.corners.reshape(-1, 2), res.reshape(-1, 2),
                                        obs.corners[outl].reshape(-1, 2), scale=round(30 / rms / 10) * 10 or 10,
                                        title="residuals across the image")
    if unc is not None:
        out["uncertainty"] = svg.heatmap(size, unc.stdev_px, vmax=0.5, title="projection uncertainty",
                                         unit="px", label_cells=False)
    else:
        out["uncertainty"] = ""
    poly = None if val is None else val.region
    out["halves"] = "" if cv is None else svg.heatmap(
        size, cv.diff_px, vmax=1.0, title="cross-validation: halves disagree by", unit="px", polygon=poly)
    out["validity"] = "" if val is None else svg.heatmap(
        size, np.where(val.trusted, 0.0, 1.0), vmax=1.0, title="trusted (blue) / not (red); green: valid region",
        unit="", polygon=poly, points=coverage.points)
    return out


def render(summary: dict, verdict: Verdict, plot_svgs: dict[str, str]) -> str:
    env = Environment(loader=PackageLoader("calibration.report", "templates"),
                      autoescape=select_autoescape(["html", "j2"]))
    return env.get_template("report.html.j2").render(s=summary, verdict=verdict, plots=plot_svgs)
