"""The sync plots as SVG, written here: histograms and time series with shaded spans. A plotting
library (matplotlib) would be a large dependency for a few charts a browser shows as they are."""
from __future__ import annotations

from html import escape

import numpy as np

W, H = 640, 300
ML, MR, MT, MB = 64, 16, 30, 42
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd")


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    if not np.isfinite(lo) or not np.isfinite(hi) or hi <= lo:
        return [lo]
    step = 10 ** np.floor(np.log10((hi - lo) / n))
    for m in (1, 2, 5, 10):
        if (hi - lo) / (step * m) <= n:
            step *= m
            break
    start = np.ceil(lo / step) * step
    return [float(v) for v in np.arange(start, hi + step * 1e-9, step)]


class Chart:
    def __init__(self, title: str, xlabel: str, ylabel: str, xlim, ylim):
        self.title, self.xlabel, self.ylabel = title, xlabel, ylabel
        x0, x1 = xlim
        y0, y1 = ylim
        if x1 <= x0:
            x1 = x0 + 1
        if y1 <= y0:
            y1 = y0 + 1
        self.xlim, self.ylim = (x0, x1), (y0, y1)
        self.items: list[str] = []
        self.legend: list[tuple[str, str]] = []

    def X(self, x):
        return ML + (np.asarray(x, float) - self.xlim[0]) / (self.xlim[1] - self.xlim[0]) * (W - ML - MR)

    def Y(self, y):
        return H - MB - (np.asarray(y, float) - self.ylim[0]) / (self.ylim[1] - self.ylim[0]) * (H - MT - MB)

    def span(self, x0: float, x1: float, colour: str = "#ffbf00", label: str | None = None) -> None:
        a, b = float(self.X(max(x0, self.xlim[0]))), float(self.X(min(x1, self.xlim[1])))
        if b > a:
            self.items.insert(0, f'<rect x="{a:.1f}" y="{MT}" width="{b - a:.1f}" height="{H - MT - MB}" '
                                 f'fill="{colour}" fill-opacity="0.25"/>')
            if label and (label, colour) not in self.legend:
                self.legend.append((label, colour))

    def bars(self, edges: np.ndarray, counts: np.ndarray, colour: str, label: str) -> None:
        for i, c in enumerate(counts):
            if c <= 0:
                continue
            x0, x1 = float(self.X(edges[i])), float(self.X(edges[i + 1]))
            y = float(self.Y(c))
            self.items.append(f'<rect x="{x0:.1f}" y="{y:.1f}" width="{max(x1 - x0 - 0.5, 0.5):.1f}" '
                              f'height="{H - MB - y:.1f}" fill="{colour}" fill-opacity="0.6"/>')
        self.legend.append((label, colour))

    def points(self, x: np.ndarray, y: np.ndarray, colour: str, label: str, r: float = 1.3) -> None:
        xs, ys = self.X(x), self.Y(np.clip(y, *self.ylim))
        if len(xs) > 4000:                       # keep files small: every n-th point
            k = int(np.ceil(len(xs) / 4000))
            xs, ys = xs[::k], ys[::k]
        self.items.append(f'<g fill="{colour}">' + "".join(
            f'<circle cx="{a:.1f}" cy="{b:.1f}" r="{r}"/>' for a, b in zip(xs, ys)) + "</g>")
        self.legend.append((label, colour))

    def hline(self, y: float, colour: str = "#555", dash: str = "4 3") -> None:
        yy = float(self.Y(y))
        self.items.append(f'<line x1="{ML}" x2="{W - MR}" y1="{yy:.1f}" y2="{yy:.1f}" stroke="{colour}" '
                          f'stroke-dasharray="{dash}"/>')

    def svg(self) -> str:
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" '
               f'font-family="sans-serif" font-size="11">',
               f'<rect width="{W}" height="{H}" fill="white"/>',
               f'<text x="{W / 2}" y="18" text-anchor="middle" font-size="13">{escape(self.title)}</text>']
        out += self.items
        out.append(f'<rect x="{ML}" y="{MT}" width="{W - ML - MR}" height="{H - MT - MB}" fill="none" '
                   f'stroke="#333"/>')
        for t in _ticks(*self.xlim):
            x = float(self.X(t))
            out.append(f'<line x1="{x:.1f}" x2="{x:.1f}" y1="{H - MB}" y2="{H - MB + 4}" stroke="#333"/>'
                       f'<text x="{x:.1f}" y="{H - MB + 15}" text-anchor="middle">{t:g}</text>')
        for t in _ticks(*self.ylim):
            y = float(self.Y(t))
            out.append(f'<line x1="{ML - 4}" x2="{ML}" y1="{y:.1f}" y2="{y:.1f}" stroke="#333"/>'
                       f'<text x="{ML - 6}" y="{y + 4:.1f}" text-anchor="end">{t:g}</text>')
        out.append(f'<text x="{(W + ML - MR) / 2}" y="{H - 8}" text-anchor="middle">{escape(self.xlabel)}</text>')
        out.append(f'<text x="14" y="{(H - MB + MT) / 2}" text-anchor="middle" '
                   f'transform="rotate(-90 14 {(H - MB + MT) / 2})">{escape(self.ylabel)}</text>')
        for i, (label, colour) in enumerate(self.legend):
            y = MT + 8 + 14 * i
            out.append(f'<rect x="{W - MR - 150}" y="{y - 8}" width="10" height="10" fill="{colour}"/>'
                       f'<text x="{W - MR - 136}" y="{y + 1}">{escape(label)}</text>')
        out.append("</svg>\n")
        return "\n".join(out)


def interval_histogram(name: str, intervals_ms: np.ndarray, period_ms: float, factor: float) -> str:
    d = np.asarray(intervals_ms, float)
    hi = max(float(np.max(d)) if len(d) else period_ms, factor * period_ms) * 1.05
    edges = np.linspace(0, hi, 121)
    counts, _ = np.histogram(d, edges)
    c = Chart(f"{name}: frame intervals ({len(d)})", "interval (ms)", "count (log10(1 + n))",
              (0, hi), (0, float(np.log10(1 + counts.max())) * 1.1 if len(d) else 1))
    c.span(factor * period_ms, hi, "#d62728", f"drop (> {factor:g} x period)")
    c.bars(edges, np.log10(1 + counts), COLOURS[0], "intervals")
    return c.svg()


def residual_series(name: str, t_s: np.ndarray, r_ms: np.ndarray, ffc: list[tuple[float, float, str]],
                    offset_ms: float | None) -> str:
    lo, hi = (float(np.min(r_ms)), float(np.max(r_ms))) if len(r_ms) else (0.0, 1.0)
    pad = max(0.5, 0.1 * (hi - lo))
    c = Chart(f"{name}: pairing residual over time", "time (s)", "residual (ms)",
              (0, float(np.max(t_s)) if len(t_s) else 1), (lo - pad, hi + pad))
    for a, b, label in ffc:
        c.span(a, b, "#ffbf00", label)
    c.points(t_s, r_ms, COLOURS[0], "residual")
    if offset_ms is not None:
        c.hline(offset_ms)
    return c.svg()
