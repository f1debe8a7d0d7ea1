"""Small inline-SVG plots for the report (no plotting library, no network): an image frame with
points or arrows, a heat map over the image, a bar chart, a residual scatter."""
from __future__ import annotations

from html import escape

import numpy as np

W_PX = 480     # drawing width of an image-shaped plot


def _frame(imagersize: tuple[int, int], width: int = W_PX, margin: int = 24):
    w, h = imagersize
    s = width / w
    return s, int(round(h * s)), margin


def _colour(t: float) -> str:
    """0..1 to a perceptually ordered blue-yellow-red ramp; >1 saturates."""
    t = float(np.clip(t, 0, 1)) if np.isfinite(t) else 1.0
    stops = [(0.0, (49, 54, 149)), (0.35, (116, 173, 209)), (0.6, (254, 224, 144)), (0.8, (244, 109, 67)),
             (1.0, (165, 0, 38))]
    for (t0, c0), (t1, c1) in zip(stops, stops[1:]):
        if t <= t1:
            a = (t - t0) / (t1 - t0)
            c = [int(round(c0[i] + a * (c1[i] - c0[i]))) for i in range(3)]
            return f"rgb({c[0]},{c[1]},{c[2]})"
    return "rgb(165,0,38)"


def _svg(width: int, height: int, body: list[str], title: str) -> str:
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
            f'viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}">'
            f'<title>{escape(title)}</title>' + "".join(body) + "</svg>")


def heatmap(imagersize, cell_values: np.ndarray, *, vmax: float, title: str, unit: str,
            label_cells: bool = False, points: np.ndarray | None = None,
            polygon: np.ndarray | None = None) -> str:
    """Cells (ny, nx) tiling the image, coloured by value / vmax; optional points drawn on top."""
    s, hh, m = _frame(imagersize)
    ny, nx = cell_values.shape
    cw, ch = W_PX / nx, hh / ny
    body = []
    for j in range(ny):
        for i in range(nx):
            val = cell_values[j, i]
            body.append(f'<rect x="{m + i * cw:.1f}" y="{m + j * ch:.1f}" width="{cw + 0.5:.1f}" '
                        f'height="{ch + 0.5:.1f}" fill="{_colour(val / vmax)}"><title>{val:.3g} {unit}</title></rect>')
            if label_cells:
                txt = "inf" if not np.isfinite(val) else f"{val:.0f}" if val >= 10 or val == int(val) else f"{val:.2f}"
                body.append(f'<text x="{m + (i + 0.5) * cw:.1f}" y="{m + (j + 0.5) * ch + 4:.1f}" '
                            f'font-size="10" text-anchor="middle" fill="#000">{txt}</text>')
    if points is not None and len(points):
        step = max(1, len(points) // 4000)
        for x, y in points[::step]:
            body.append(f'<circle cx="{m + x * s:.1f}" cy="{m + y * s:.1f}" r="0.8" fill="#000" opacity="0.5"/>')
    if polygon is not None and len(polygon) >= 4:
        pts = " ".join(f"{m + x * s:.1f},{m + y * s:.1f}" for x, y in polygon)
        body.append(f'<polygon points="{pts}" fill="none" stroke="#1a9850" stroke-width="2.5" '
                    f'stroke-dasharray="6,3"/>')
    body.append(f'<rect x="{m}" y="{m}" width="{W_PX}" height="{hh}" fill="none" stroke="#333"/>')
    body.append(f'<text x="{m}" y="{m - 8}" font-size="12">{escape(title)} (colour scale 0 .. {vmax:.3g} {unit})</text>')
    return _svg(W_PX + 2 * m, hh + 2 * m, body, title)


def residual_arrows(imagersize, corners: np.ndarray, residuals: np.ndarray, outliers: np.ndarray | None,
                    *, scale: float, title: str) -> str:
    """Every corner as a dot with its residual drawn as a line, magnified ``scale`` times; outlier
    corners in red."""
    s, hh, m = _frame(imagersize)
    body = [f'<rect x="{m}" y="{m}" width="{W_PX}" height="{hh}" fill="#fafafa" stroke="#333"/>']
    ok = np.isfinite(corners).all(axis=-1) & np.isfinite(residuals).all(axis=-1)
    pts, res = corners[ok], residuals[ok]
    step = max(1, len(pts) // 3000)
    for (x, y), (dx, dy) in zip(pts[::step], res[::step]):
        x0, y0 = m + x * s, m + y * s
        body.append(f'<line x1="{x0:.1f}" y1="{y0:.1f}" x2="{x0 + dx * scale * s:.1f}" '
                    f'y2="{y0 + dy * scale * s:.1f}" stroke="#2166ac" stroke-width="0.8"/>')
    if outliers is not None and len(outliers):
        for x, y in outliers:
            body.append(f'<circle cx="{m + x * s:.1f}" cy="{m + y * s:.1f}" r="2.5" fill="none" stroke="#b2182b"/>')
    body.append(f'<text x="{m}" y="{m - 8}" font-size="12">{escape(title)} (residuals x{scale:g}; red: rejected corners)</text>')
    return _svg(W_PX + 2 * m, hh + 2 * m, body, title)


def scatter(residuals: np.ndarray, *, title: str, rms: float) -> str:
    """Residual vectors as points around the origin, with the RMS circle."""
    size, m = 260, 24
    r = residuals[np.isfinite(residuals).all(axis=-1)]
    lim = max(float(np.percentile(np.abs(r), 99.5)) if len(r) else 1.0, 1e-3) * 1.1
    c = m + size / 2
    k = size / 2 / lim
    body = [f'<rect x="{m}" y="{m}" width="{size}" height="{size}" fill="#fafafa" stroke="#333"/>',
            f'<line x1="{m}" y1="{c}" x2="{m + size}" y2="{c}" stroke="#bbb"/>',
            f'<line x1="{c}" y1="{m}" x2="{c}" y2="{m + size}" stroke="#bbb"/>']
    step = max(1, len(r) // 4000)
    for dx, dy in r[::step]:
        body.append(f'<circle cx="{c + dx * k:.1f}" cy="{c + dy * k:.1f}" r="1" fill="#2166ac" opacity="0.4"/>')
    body.append(f'<circle cx="{c}" cy="{c}" r="{rms * k:.1f}" fill="none" stroke="#b2182b"/>')
    body.append(f'<text x="{m}" y="{m - 8}" font-size="12">{escape(title)} (axes +-{lim:.2f} px; circle: RMS {rms:.3f} px)</text>')
    return _svg(size + 2 * m + 40, size + 2 * m, body, title)


def bars(labels: list[str], values: np.ndarray, *, title: str, unit: str, highlight: set[int] = frozenset()) -> str:
    n = max(len(values), 1)
    bw = max(4, min(18, 600 // n))
    h, m = 160, 24
    vmax = float(np.nanmax(values)) if len(values) and np.isfinite(np.nanmax(values)) else 1.0
    vmax = max(vmax, 1e-6)
    body = []
    for i, (lab, v) in enumerate(zip(labels, values)):
        bh = 0 if not np.isfinite(v) else v / vmax * h
        fill = "#b2182b" if i in highlight else "#4393c3"
        body.append(f'<rect x="{m + i * bw}" y="{m + h - bh:.1f}" width="{bw - 1}" height="{bh:.1f}" '
                    f'fill="{fill}"><title>{escape(lab)}: {v:.3f} {unit}</title></rect>')
    body.append(f'<line x1="{m}" y1="{m + h}" x2="{m + n * bw}" y2="{m + h}" stroke="#333"/>')
    body.append(f'<text x="{m}" y="{m - 8}" font-size="12">{escape(title)} (max {vmax:.3f} {unit}; hover for names)</text>')
    return _svg(n * bw + 2 * m, h + 2 * m, body, title)
