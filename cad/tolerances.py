"""The tolerance stack-up: how far each camera may sit from its CAD pose, from the datum features
(cad/datums.py), the fits (the screws' play in their clearance holes, the Boson's in its bore) and the
printer's and the machinist's position tolerances (``printing.printer.tolerance_mm``,
``enclosure.heat_sink.tolerance_mm``).

Analytic (:func:`stack_up`): each location of a camera's chain is a set of point contacts with rows
``A`` (cad/datums.py); a contact off by ``d`` along its normal moves the located part by the twist
``A^+ d`` (exactly constrained: ``A^-1``). Every term of every contact (a play or a tolerance, +- its
value) is one independent input; the camera's twist is the sum over its chain (small motions add),
written at the camera's origin in its body axes (x forward, y left, z up; mm and rad). Per axis:
worst case = sum of |contribution|; RSS = root sum of squares; 1-sigma = RSS / 3 (each +- tolerance
read as a 3-sigma bound, the RSS convention). Relative to the ZED X (what ``calibrate rig`` refines)
the ZED's chain enters with the opposite sign.

Independent path (:func:`monte_carlo`): draw every term, solve each location's contact equations
exactly (a rigid motion of the located part, nonlinear), compose the chain's motions as 4x4 poses and
read the camera's error off the composed pose; tests hold the two to each other.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.frames import Pose, matrix_to_rotvec, rotvec_to_matrix

from .datums import DOF, Location

#: a +- tolerance is read as this many sigmas (the RSS convention)
SIGMAS_PER_TOLERANCE = 3.0


@dataclass(frozen=True)
class PoseUncertainty:
    """A camera's expected pose error, per axis of its body frame: translations mm, rotations deg."""
    camera: str
    relative_to: str                 # "case" (the floor of case_lower) or the camera it is relative to
    worst: tuple[float, ...]         # x, y, z mm; roll, pitch, yaw deg
    rss: tuple[float, ...]
    covariance: np.ndarray           # (6, 6) 1-sigma covariance of (x, y, z mm, roll, pitch, yaw rad)
    terms: int

    @property
    def sigma(self) -> tuple[float, ...]:
        """1-sigma per axis (mm, deg)."""
        s = np.sqrt(np.diag(self.covariance))
        return tuple(float(v) for v in np.concatenate([s[:3], np.degrees(s[3:])]))

    def as_dict(self) -> dict:
        r = lambda v: [round(float(x), 5) for x in v]
        return {"relative_to": self.relative_to, "axes": "camera body frame: x forward, y left, z up",
                "worst_case": {"xyz_mm": r(self.worst[:3]), "rpy_deg": r(self.worst[3:])},
                "rss": {"xyz_mm": r(self.rss[:3]), "rpy_deg": r(self.rss[3:])},
                "sigma": {"xyz_mm": r(self.sigma[:3]), "rpy_deg": r(self.sigma[3:])},
                "inputs": self.terms}


def contribution_matrix(chain: tuple[Location, ...], frame: Pose) -> tuple[np.ndarray, list[str]]:
    """(6, n) the camera's twist (mm, rad at ``frame``) per unit of each of the chain's n terms (each
    column is one term at its full +- value; a shared term moves every contact of its feature at
    once), and the terms' names."""
    cols, names = [], []
    for loc in chain:
        A = loc.rows(frame=frame)
        Ap = np.linalg.pinv(A)
        i = 0
        for f in loc.features:
            shared: dict[str, int] = {}
            for c in f.contacts:
                for name, value, is_shared in c.terms:
                    if is_shared and name in shared:      # one input moves every contact of the feature
                        cols[shared[name]] = cols[shared[name]] + Ap[:, i] * value
                        continue
                    if is_shared:
                        shared[name] = len(cols)
                    cols.append(Ap[:, i] * value)
                    names.append(f"{loc.name}: {f.name}: {name}")
                i += 1
    return np.array(cols).T.reshape(6, -1), names


def _summary(camera: str, relative_to: str, J: np.ndarray) -> PoseUncertainty:
    conv = np.array([1, 1, 1, 180 / np.pi, 180 / np.pi, 180 / np.pi])
    worst = np.abs(J).sum(axis=1) * conv
    rss = np.sqrt((J ** 2).sum(axis=1)) * conv
    cov = J @ J.T / SIGMAS_PER_TOLERANCE ** 2
    return PoseUncertainty(camera, relative_to, tuple(float(v) for v in worst), tuple(float(v) for v in rss),
                           cov, J.shape[1])


def stack_up(locations: dict[str, tuple[Location, ...]], camera: str, relative_to: str | None = None,
             frame: Pose | None = None) -> PoseUncertainty:
    """``camera``'s pose uncertainty against the case floor, or relative to the camera ``relative_to``
    (its chain enters with the opposite sign), at ``frame`` (default: the camera's body frame)."""
    chain = locations[camera]
    f = chain[-1].frame if frame is None else frame
    J, _ = contribution_matrix(chain, f)
    if relative_to is not None:
        Jo, _ = contribution_matrix(locations[relative_to], f)
        J = np.hstack([J, -Jo])
    return _summary(camera, relative_to or "case", J)


# ----------------------------------------------------------------------------- the independent path
def _exp(xi: np.ndarray) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3] = rotvec_to_matrix(xi[3:])
    M[:3, 3] = xi[:3]
    return M


def seat(loc: Location, offsets: np.ndarray, iterations: int = 8) -> np.ndarray:
    """The rigid motions (k, 4, 4; rig frame) of ``loc``'s moving part when its contacts' mating faces
    are ``offsets`` (k, n contacts; mm along each normal) away: solves ``n_i . (M p_i - p_i) = offsets_i``
    exactly (Gauss-Newton on ``M <- exp(d) M``; least squares when over-constrained)."""
    contacts = loc.contacts()
    P = np.array([c.point for c in contacts], float)
    N = np.array([c.normal for c in contacts], float)
    k = offsets.shape[0]
    M = np.tile(np.eye(4), (k, 1, 1))
    for _ in range(iterations):
        Q = np.einsum("kab,nb->kna", M[:, :3, :3], P) + M[:, None, :3, 3]          # moved points
        r = np.einsum("na,kna->kn", N, Q - P) - offsets
        J = np.concatenate([np.broadcast_to(N, Q.shape), np.cross(Q, N)], axis=2)   # (k, n, 6)
        step = -np.linalg.solve(np.einsum("kni,knj->kij", J, J), np.einsum("kni,kn->ki", J, r))
        E = np.tile(np.eye(4), (k, 1, 1))
        for i in range(k):
            E[i, :3, :3] = rotvec_to_matrix(step[i, 3:])
        E[:, :3, 3] = step[:, :3]
        M = E @ M
        if np.abs(step).max() < 1e-13:
            break
    return M


def _chain_motion(chain: tuple[Location, ...], draws: list[np.ndarray]) -> np.ndarray:
    """The camera's motions in the rig (k, 4, 4): each location's part seated on its already moved base."""
    M = None
    for loc, d in zip(chain, draws):
        S = seat(loc, d)
        M = S if M is None else M @ S
    return M


def _draw(rng, chain, n: int, distribution: str) -> list[np.ndarray]:
    """Per location (n, contacts) offsets: every term drawn once per sample (a shared term once per feature)."""
    out = []
    for loc in chain:
        cols = []
        for f in loc.features:
            shared: dict[str, np.ndarray] = {}
            for c in f.contacts:
                total = np.zeros(n)
                for name, value, is_shared in c.terms:
                    u = (rng.uniform(-1, 1, n) if distribution == "uniform" else
                         rng.normal(0, 1 / SIGMAS_PER_TOLERANCE, n))
                    if is_shared:
                        u = shared.setdefault(name, u)
                    total += value * u
                cols.append(total)
        out.append(np.stack(cols, axis=1))
    return out


def _rotvec_deg(R: np.ndarray) -> np.ndarray:
    return np.degrees(np.array([matrix_to_rotvec(r) for r in R]))


def monte_carlo(locations: dict[str, tuple[Location, ...]], camera: str, relative_to: str | None = None,
                n: int = 2000, seed: int = 0, distribution: str = "normal") -> np.ndarray:
    """(n, 6) sampled errors of ``camera``'s pose (x, y, z mm, roll, pitch, yaw deg; its body frame, or
    relative to ``relative_to``): every term drawn (normal with sigma = tolerance / 3, or uniform over
    +- the tolerance), every location seated exactly, the chain composed as 4x4 poses."""
    rng = np.random.default_rng(seed)
    chain = locations[camera]
    T = chain[-1].frame.matrix()
    Tc = _chain_motion(chain, _draw(rng, chain, n, distribution)) @ T
    if relative_to is None:
        E = np.linalg.inv(T) @ Tc
    else:
        other = locations[relative_to]
        To = other[-1].frame.matrix()
        To2 = _chain_motion(other, _draw(rng, other, n, distribution)) @ To
        nominal = np.linalg.inv(To) @ T
        E = np.linalg.inv(nominal) @ (np.linalg.inv(To2) @ Tc)
    return np.concatenate([E[:, :3, 3], _rotvec_deg(E[:, :3, :3])], axis=1)


def axis_names() -> tuple[str, ...]:
    return DOF


# ----------------------------------------------------------------------------- clamps
def clamp_margins(locations: dict[str, tuple[Location, ...]]) -> dict[str, dict]:
    """Per clamp (``"<camera>: <clamp>"``): the standoff it keeps to the base (mm) and how much of it
    the tolerances may close, worst case (sum) and 3-sigma RSS; a clamp whose standoff can close lands
    on the base before it presses the part (cad/datums.py fails it)."""
    out = {}
    for cam, chain in locations.items():
        for loc in chain:
            for cl in loc.clamps:
                v = np.array([abs(t) for _, t, _ in cl.standoff_terms])
                out[f"{cam}: {cl.name}"] = dict(standoff_mm=cl.standoff_mm, worst_mm=float(v.sum()),
                                                rss_mm=float(np.sqrt((v ** 2).sum())),
                                                margin_mm=float(cl.standoff_mm - v.sum()))
    return out
