"""Camera rigs: construction, docs/interfaces.md section 2 rig files (cv2.FileStorage) and projection.

Projection uses cv2.projectPoints, so the simulator and evaluation do not share code with the
C core they test.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np


def _coeffs(dist) -> np.ndarray:
    """OpenCV's distortion coefficients k1 k2 p1 p2 k3 k4 k5 k6, zero where not given."""
    d = np.zeros(8)
    dist = np.asarray(dist, float).ravel()[:8]
    d[:len(dist)] = dist
    return d


def _radial(d: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """OpenCV's radial factor (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)."""
    return (1 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]))) / (1 + r2 * (d[5] + r2 * (d[6] + r2 * d[7])))


def _radial_map(dist: tuple, r: np.ndarray) -> np.ndarray:
    """OpenCV's radial distortion of a normalised radius r."""
    return r * _radial(_coeffs(dist), r * r)


def _distort(d: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's lens model: normalised (x, y) to distorted normalised coordinates."""
    r2 = x * x + y * y
    rad = _radial(d, r2)
    return (x * rad + 2 * d[2] * x * y + d[3] * (r2 + 2 * x * x),
            y * rad + d[2] * (r2 + 2 * y * y) + 2 * d[3] * x * y)


def normalise(K: np.ndarray, dist, pix: np.ndarray, iters: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """The normalised image points (N x 2) the lens maps to pixels pix (N x 2), and which pixels
    have one. cv2.undistortPoints' fixed-point iteration starts it; damped Newton steps finish it:
    the fixed point stalls where the distorted radius grows slowly with the true one (a strong
    barrel lens's picture corners) and leaves pixels off there. Beyond the fold of the lens's
    polynomial a pixel has no ray (no light reaches it)."""
    K = np.asarray(K, float)
    d = _coeffs(dist)
    pix = np.asarray(pix, float).reshape(-1, 2)
    xn = cv2.undistortPointsIter(pix.reshape(-1, 1, 2), K, d, None, None,
                                 (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)).reshape(-1, 2)
    tx = (pix[:, 0] - K[0, 2]) / K[0, 0]
    ty = (pix[:, 1] - K[1, 2]) / K[1, 1]
    x, y = xn[:, 0].copy(), xn[:, 1].copy()
    h = 1e-6
    # a pixel leaves the iteration once it is met to 1e-9 px (Newton's next step would not move it
    # measurably): most are after one or two steps, and only those left cost the next one
    tol2 = (1e-9 / max(K[0, 0], K[1, 1])) ** 2
    live = np.arange(len(x))
    for _ in range(iters):
        xa, ya, txa, tya = x[live], y[live], tx[live], ty[live]
        fx, fy = _distort(d, xa, ya)
        ex, ey = fx - txa, fy - tya
        e0 = ex * ex + ey * ey
        keep = e0 > tol2
        if not keep.all():
            live, xa, ya, txa, tya, fx, fy, ex, ey, e0 = (
                a[keep] for a in (live, xa, ya, txa, tya, fx, fy, ex, ey, e0))
        if live.size == 0:
            break
        ax, ay = _distort(d, xa + h, ya)
        bx, by = _distort(d, xa, ya + h)
        j11, j21 = (ax - fx) / h, (ay - fy) / h
        j12, j22 = (bx - fx) / h, (by - fy) / h
        det = j11 * j22 - j12 * j21
        ok = np.abs(det) > 1e-9
        det = np.where(ok, det, 1.0)
        sx = np.where(ok, (j22 * ex - j12 * ey) / det, 0.0)
        sy = np.where(ok, (j11 * ey - j21 * ex) / det, 0.0)
        step = np.zeros_like(xa)
        for t in (1.0, 0.5, 0.25, 0.125):  # the longest step that lowers the error
            gx, gy = _distort(d, xa - t * sx, ya - t * sy)
            better = (step == 0) & ((gx - txa) ** 2 + (gy - tya) ** 2 < e0)
            step[better] = t
        x[live] = xa - step * sx
        y[live] = ya - step * sy
    fx, fy = _distort(d, x, y)
    has_ray = np.hypot((fx - tx) * K[0, 0], (fy - ty) * K[1, 1]) < 1e-3
    return np.stack([x, y], axis=1), has_ray


@functools.lru_cache(maxsize=256)
def _field_r2(dist: tuple) -> float:
    """Camera.field_r2 for these coefficients: scanned in steps of 1/256 up to r = 20 (cached:
    Camera.project asks on every call)."""
    r = np.arange(1, 20 * 256 + 1) / 256.0
    bad = np.flatnonzero(~(np.diff(np.concatenate([[0.0], _radial_map(dist, r)])) > 0))
    return float((r[bad[0]] - 1 / 256.0) ** 2) if len(bad) else float("inf")


@dataclass
class Camera:
    name: str
    K: np.ndarray            # 3x3
    dist: np.ndarray         # (5,) or (4,) or (8,)
    rvec: np.ndarray         # (3,) world -> camera
    tvec: np.ndarray         # (3,)
    width: int = 768
    height: int = 576
    sigma_px: float = 2.0

    @property
    def R(self) -> np.ndarray:
        return cv2.Rodrigues(self.rvec.reshape(3, 1))[0]

    @property
    def centre(self) -> np.ndarray:
        return -self.R.T @ self.tvec

    def depth(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        return (X @ self.R.T + self.tvec)[:, 2]

    @property
    def field_r2(self) -> float:
        """The lens model's field: normalised x^2 + y^2 up to the first maximum of the radial map
        (_radial_map). Beyond it the polynomial folds points back into the picture; a real lens
        shows nothing of them. inf when it never folds (r <= 20). The core computes the same
        (mvt_camera.c); both are checked against the analytic fold of a k1-only lens
        (tests/test_camera.c, tests/python/test_tools.py)."""
        return _field_r2(tuple(np.asarray(self.dist, float).ravel()[:8]))

    def in_field(self, X: np.ndarray) -> np.ndarray:
        """World points (N,3) the camera can image: in front, within the lens model's field."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        xc = X @ self.R.T + self.tvec
        with np.errstate(divide="ignore", invalid="ignore"):
            r2 = (xc[:, 0] ** 2 + xc[:, 1] ** 2) / xc[:, 2] ** 2
        return (xc[:, 2] > 1e-3) & (r2 <= self.field_r2)

    def project(self, X: np.ndarray) -> np.ndarray:
        """World points (N,3) -> raw distorted pixels (N,2); NaN for points outside the camera's
        field (behind it, or beyond the distortion's fold, where cv2.projectPoints would fold them
        back into the picture)."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        uv, _ = cv2.projectPoints(X.reshape(-1, 1, 3), self.rvec.reshape(3, 1), self.tvec.reshape(3, 1), self.K,
                                  self.dist)
        uv = uv.reshape(-1, 2)
        uv[~self.in_field(X)] = np.nan
        return uv

    def project_jacobian(self, X: np.ndarray) -> np.ndarray:
        """d(u, v)/d(X, Y, Z) of one world point (2x3), from cv2.projectPoints' own Jacobian."""
        X = np.asarray(X, dtype=np.float64).reshape(1, 1, 3)
        _, J = cv2.projectPoints(X, self.rvec.reshape(3, 1), self.tvec.reshape(3, 1), self.K, self.dist)
        d_rvec, d_tvec = J[:, 0:3], J[:, 3:6]
        # X_cam = R X + t, so d/dX = d/dt * R
        return d_tvec @ self.R

    def in_image(self, uv: np.ndarray, margin: float = 0.0) -> np.ndarray:
        uv = np.atleast_2d(uv)
        return ((uv[:, 0] >= margin) & (uv[:, 0] <= self.width - 1 - margin) & (uv[:, 1] >= margin)
                & (uv[:, 1] <= self.height - 1 - margin))


@dataclass
class Rig:
    cameras: list[Camera]
    volume_min: np.ndarray
    volume_max: np.ndarray
    frame_rate: float = 25.0
    extra: dict = field(default_factory=dict)
    # static occluders (furniture, pillars): [{"name": str, "min": (3,), "max": (3,)}], world metres
    occluders: list = field(default_factory=list)

    def write(self, path: str | Path) -> None:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
        fs.startWriteStruct("cameras", cv2.FileNode_SEQ)
        for c in self.cameras:
            fs.startWriteStruct("", cv2.FileNode_MAP)
            fs.write("name", c.name)
            fs.write("image_width", int(c.width))
            fs.write("image_height", int(c.height))
            fs.write("camera_matrix", np.asarray(c.K, dtype=np.float64))
            fs.write("distortion_coefficients", np.asarray(c.dist, dtype=np.float64).reshape(1, -1))
            fs.write("rvec", np.asarray(c.rvec, dtype=np.float64).reshape(3, 1))
            fs.write("tvec", np.asarray(c.tvec, dtype=np.float64).reshape(3, 1))
            fs.write("sigma_px", float(c.sigma_px))
            fs.endWriteStruct()
        fs.endWriteStruct()
        fs.write("volume_min", np.asarray(self.volume_min, dtype=np.float64).reshape(3, 1))
        fs.write("volume_max", np.asarray(self.volume_max, dtype=np.float64).reshape(3, 1))
        fs.write("frame_rate", float(self.frame_rate))
        if self.occluders:
            fs.startWriteStruct("occluders", cv2.FileNode_SEQ)
            for o in self.occluders:
                fs.startWriteStruct("", cv2.FileNode_MAP)
                if o.get("name"):
                    fs.write("name", str(o["name"]))
                fs.write("min", np.asarray(o["min"], dtype=np.float64).reshape(3, 1))
                fs.write("max", np.asarray(o["max"], dtype=np.float64).reshape(3, 1))
                fs.endWriteStruct()
            fs.endWriteStruct()
        fs.release()
        # docs/interfaces.md section 2 names the OpenCV 4 header; OpenCV 5 writes "%YAML 1.2".
        text = Path(path).read_text()
        if not text.startswith("%YAML:1.0"):
            Path(path).write_text("%YAML:1.0\n" + text.split("\n", 1)[1])

    @staticmethod
    def read(path: str | Path) -> "Rig":
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        if not fs.isOpened():
            raise FileNotFoundError(path)
        cams = []
        node = fs.getNode("cameras")
        for i in range(node.size()):
            n = node.at(i)
            dist_node = n.getNode("distortion_coefficients")
            dist = dist_node.mat().ravel() if not dist_node.empty() else np.zeros(5)
            sig = n.getNode("sigma_px")
            cams.append(Camera(name=n.getNode("name").string(), K=n.getNode("camera_matrix").mat(), dist=dist,
                               rvec=n.getNode("rvec").mat().ravel(), tvec=n.getNode("tvec").mat().ravel(),
                               width=int(n.getNode("image_width").real()), height=int(n.getNode("image_height").real()),
                               sigma_px=sig.real() if not sig.empty() else 2.0))
        vmin = fs.getNode("volume_min").mat().ravel()
        vmax = fs.getNode("volume_max").mat().ravel()
        fr = fs.getNode("frame_rate")
        rate = fr.real() if not fr.empty() else 25.0
        occluders = []
        occ = fs.getNode("occluders")
        for i in range(occ.size() if not occ.empty() else 0):
            o = occ.at(i)
            nm = o.getNode("name")
            occluders.append({"name": nm.string() if not nm.empty() else "",
                              "min": _vector3(o.getNode("min")), "max": _vector3(o.getNode("max"))})
        fs.release()
        return Rig(cams, vmin, vmax, rate, occluders=occluders)


def _vector3(node) -> np.ndarray:
    """A 3-vector written as an OpenCV matrix or as a plain YAML list."""
    if node.isSeq():
        return np.array([node.at(i).real() for i in range(node.size())], dtype=np.float64)
    return node.mat().ravel().astype(np.float64)


def look_at(name: str, position, target, K: np.ndarray, dist, width: int = 768, height: int = 576,
            sigma_px: float = 2.0, roll_deg: float = 0.0) -> Camera:
    """A camera at `position` looking at `target`, image y axis pointing down toward world -z."""
    c = np.asarray(position, dtype=np.float64)
    f = np.asarray(target, dtype=np.float64) - c
    f /= np.linalg.norm(f)
    up = np.array([0.0, 0.0, 1.0])
    if abs(f @ up) > 0.99:  # looking straight down: pick world y as image "up"
        up = np.array([0.0, 1.0, 0.0])
    x = np.cross(f, up)
    x /= np.linalg.norm(x)
    y = np.cross(f, x)
    R = np.stack([x, y, f])  # rows: camera axes in world
    if roll_deg:
        a = np.deg2rad(roll_deg)
        Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        R = Rz @ R
    rvec = cv2.Rodrigues(R)[0].ravel()
    tvec = -R @ c
    return Camera(name, np.asarray(K, dtype=np.float64), np.asarray(dist, dtype=np.float64), rvec, tvec, width, height,
                  sigma_px)


def intrinsics(fx: float, fy: float, cx: float, cy: float, skew: float = 0.0) -> np.ndarray:
    return np.array([[fx, skew, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def smartroom(sigma_px: float = 2.0) -> Rig:
    """The Experiment 1 rig: a 6 x 5 x 3 m room, four wide-angle cameras high in the corners and
    one wide-angle zenithal camera, 768 x 576 at 25 fps (the PKF paper's UPC SmartRoom set-up;
    the paper gives no geometry, this one is documented in docs/experiment1.md)."""
    L, W = 6.0, 5.0
    wide = intrinsics(420.0, 420.0, 383.5, 287.5)
    d = [-0.22, 0.06, 0.0005, -0.0004, -0.006]
    tgt = [L / 2, W / 2, 0.9]
    cams = [
        look_at("cam0", [0.15, 0.15, 2.75], tgt, wide, d, sigma_px=sigma_px),
        look_at("cam1", [L - 0.15, 0.15, 2.75], tgt, wide, d, sigma_px=sigma_px),
        look_at("cam2", [L - 0.15, W - 0.15, 2.75], tgt, wide, d, sigma_px=sigma_px),
        look_at("cam3", [0.15, W - 0.15, 2.75], tgt, wide, d, sigma_px=sigma_px),
        look_at("cam4", [L / 2, W / 2, 2.95], [L / 2, W / 2, 0.0], intrinsics(300.0, 300.0, 383.5, 287.5),
                [-0.18, 0.035, 0.0, 0.0, -0.003], sigma_px=sigma_px),
    ]
    return Rig(cams, np.array([0.0, 0.0, 0.0]), np.array([L, W, 2.5]), 25.0)


def lens_reach(cam: Camera) -> float:
    """How far the lens model reaches across the picture: the largest distorted radius it forms (at
    its fold) over the farthest picture corner's distorted normalised radius. Under 1 the polynomial
    turns back inside the picture: pixels beyond have no ray, which is right only for the dark beyond
    a fisheye's image circle; where the picture shows the room there, a calibration showing it has
    extrapolated past its boards. inf when it never folds."""
    corners = np.array([[0, 0], [cam.width - 1, 0], [0, cam.height - 1], [cam.width - 1, cam.height - 1]], float)
    xd = (corners[:, 0] - cam.K[0, 2]) / cam.K[0, 0]
    yd = (corners[:, 1] - cam.K[1, 2]) / cam.K[1, 1]
    rd = float(np.max(np.hypot(xd, yd)))
    r2 = cam.field_r2
    if not np.isfinite(r2):
        return float("inf")
    return float(_radial_map(tuple(np.asarray(cam.dist, float).ravel()[:8]), np.array([np.sqrt(r2)]))[0]) / rd


def random_rig(rng: np.random.Generator, n_cameras: int, room=(7.0, 6.0, 3.0), width: int | None = None,
               height: int | None = None) -> Rig:
    """A rig built differently from smartroom(): random room size, positions on the walls, random
    intrinsics (focal, off-centre principal point, aspect, skew-free), random distortion of either
    sign, random image size and roll. For generality tests."""
    L = rng.uniform(4.0, room[0] + 2)
    W = rng.uniform(4.0, room[1] + 2)
    H = rng.uniform(2.6, room[2] + 0.5)
    cams = []
    for k in range(n_cameras):
        a = 2 * np.pi * (k + rng.uniform(-0.3, 0.3)) / n_cameras
        pos = np.array([L / 2 + 0.5 * L * np.cos(a) * 0.95, W / 2 + 0.5 * W * np.sin(a) * 0.95, H - rng.uniform(0.05, 0.6)])
        tgt = np.array([L / 2 + rng.uniform(-0.7, 0.7), W / 2 + rng.uniform(-0.7, 0.7), rng.uniform(1.0, 1.4)])
        w = width or int(rng.choice([640, 768, 1024, 1280]))
        h = height or int(w * rng.choice([0.75, 0.5625]))
        f = rng.uniform(0.45, 0.8) * w
        K = intrinsics(f, f * rng.uniform(0.97, 1.03), w / 2 + rng.uniform(-0.06, 0.06) * w,
                       h / 2 + rng.uniform(-0.06, 0.06) * h)
        k1 = rng.uniform(-0.3, 0.1)
        dist = [k1, rng.uniform(-0.02, 0.08), rng.uniform(-1e-3, 1e-3), rng.uniform(-1e-3, 1e-3), rng.uniform(-0.01, 0.005)]
        cam = look_at(f"c{k}_{rng.integers(1000)}", pos, tgt, K, dist, w, h, sigma_px=2.0,
                      roll_deg=rng.uniform(-8, 8))
        # A calibration is valid over the picture it was made from: the radial map must still rise
        # 10 % beyond the image corners. A draw that folds inside is flattened (no extra random draws,
        # so rigs whose lenses were valid stay as they were).
        while lens_reach(cam) <= 1.1:
            cam.dist[[0, 1, 4]] *= 0.8
        cams.append(cam)
    return Rig(cams, np.array([0.0, 0.0, 0.0]), np.array([L, W, 2.5]), 25.0)
