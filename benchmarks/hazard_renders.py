"""What a photo of the night sky carries besides stars, drawn onto the real photos of
``../shared/realdata`` for ``photo_hazards.py``: captions burnt in, the Moon's glow and disc,
hot pixels alone or in clusters, satellite and aircraft trails, and partial clouds.

Each renderer takes an RGB image (H, W, 3) as float64 grey levels and a seeded generator, and
returns the altered image (same shape, not clipped) and, for clouds, the cloud cover (H, W) in
[0, 1]. The captions are drawn with Pillow's scalable default font (Pillow >= 10.1).
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont
from scipy import ndimage

# text, height (px, or a fraction of the image height when < 1), place, grey level
CAPTIONS: tuple[tuple[str, float, str, int], ...] = (
    ("2024-03-15 22:14:07", 16, "bottom right", 255),
    ("2024-03-15 22:14:07", 28, "bottom right", 255),
    ("(c) Jane Doe 2024", 12, "top left", 255),
    ("ISO 3200 f/2.8 30s", 20, "bottom left", 255),
    ("(c) Jane Doe 2024", 40, "centre", 255),
    ("2024/03/15 22:14", 60, "bottom right", 255),
    ("2024/03/15 22:14", 24, "top right", 180),
    ("Canon EOS R6  ISO 6400\n2024-08-12 23:41:05", 1 / 14, "bottom left", 255),
    ("(c) 2024 Night Sky Photo", 1 / 9, "centre", 255),
    ("ALLSKY CAM 3  exposure 20 s  gain 300", 1 / 24, "top left", 200),
    ("Milky Way over the lake 2023", 0.06, "top", 255),
    ("f/1.8 15s ISO1600", 0.07, "bottom right", 255),
    ("PHOTO", 0.16, "centre left", 255),
    ("23:59:59", 0.04, "top left", 255),
    ("www.example-astro.net", 0.05, "bottom", 240),
)
"""15 captions: dates, names, camera settings, a web address; 12-166 px high on these photos."""


def caption(rgb: np.ndarray, spec: tuple[str, float, str, int]) -> np.ndarray:
    """``rgb`` with the caption ``spec`` (:data:`CAPTIONS`) drawn in its grey level."""
    text, height, place, level = spec
    image = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    w, h = image.size
    size = int(max(12, height * h if height < 1 else height))
    draw, font = ImageDraw.Draw(image), ImageFont.load_default(size=size)
    box = draw.multiline_textbbox((0, 0), text, font=font)
    tw, th = box[2] - box[0], box[3] - box[1]
    x = {"left": 8, "right": w - tw - 8}.get(place.split()[-1], (w - tw) / 2)
    x = w * 0.1 if place == "centre left" else x
    y = {"top": 8, "bottom": h - th - 12}.get(place.split()[0], h / 2)
    draw.multiline_text((x, y), text, font=font, fill=(level,) * 3)
    return np.asarray(image, dtype=np.float64)


def logo(rgb: np.ndarray) -> np.ndarray:
    """``rgb`` with a logo (a ring and a bar) drawn in white at the top right."""
    image = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    w, h = image.size
    r = h // 16
    cx, cy = w - 2 * r, 2 * r
    draw = ImageDraw.Draw(image)
    draw.ellipse((cx - r, cy - r, cx + r, cy + r), outline=(255,) * 3, width=max(2, r // 5))
    draw.rectangle((cx - 3 * r, cy + 1.4 * r, cx + r, cy + 1.4 * r + max(3, r // 4)), fill=(255,) * 3)
    return np.asarray(image, dtype=np.float64)


def _distance(shape: tuple[int, ...], cx: float, cy: float) -> np.ndarray:
    """Distance (in image widths) of every pixel from (cx, cy), given in widths and heights."""
    h, w = shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    return np.hypot(xx - cx * w, yy - cy * h) / w


GLOWS = ((-0.1, -0.1, 400.0, 0.35), (0.5, 1.25, 300.0, 0.5), (1.05, 0.5, 250.0, 0.25))
"""The Moon's glow: its centre (widths, heights; outside the frame), peak (grey levels) and scale
(widths); it falls with the cube of the distance, a little redder than white."""


def glow(rgb: np.ndarray, spec: tuple[float, float, float, float]) -> np.ndarray:
    cx, cy, amplitude, scale = spec
    light = amplitude * (scale / (_distance(rgb.shape, cx, cy) + scale)) ** 3
    return rgb + light[..., None] * np.array([1.0, 0.95, 0.85])


MOONS = ((0.8, 0.25, 0.05), (0.3, 0.7, 0.08), (0.5, 0.5, 0.04))
"""The Moon in the frame: centre (widths, heights) and radius (widths), saturated, with a glow."""


def moon(rgb: np.ndarray, spec: tuple[float, float, float]) -> np.ndarray:
    cx, cy, radius = spec
    r = _distance(rgb.shape, cx, cy)
    light = np.where(r < radius, 400.0, 0.0) + 150.0 * (radius / np.maximum(r, radius)) ** 2
    return rgb + light[..., None]


HOT_SHAPES = {"single": ((0, 0),), "pair": ((0, 0), (0, 1)), "triple": ((0, 0), (0, 1), (1, 0))}


def hot_pixels(rgb: np.ndarray, shape: str, share: float, rng: np.random.Generator) -> np.ndarray:
    """``rgb`` with ``share`` of its pixels hot (80-255 grey levels in every channel), in
    clusters of :data:`HOT_SHAPES` ``[shape]``."""
    out = rgb.copy()
    h, w = rgb.shape[:2]
    offsets = HOT_SHAPES[shape]
    n = int(share * h * w / len(offsets))
    ys, xs, level = rng.integers(1, h - 2, n), rng.integers(1, w - 2, n), rng.uniform(80, 255, n)
    for dy, dx in offsets:
        out[ys + dy, xs + dx] = np.maximum(out[ys + dy, xs + dx], level[:, None])
    return out


TRAILS = ((1, 2, 255, False), (3, 3, 220, False), (2, 2, 255, True))
"""Trails across the frame: how many, their width (px), grey level, and whether dashed (an
aircraft's blinking lights)."""


def trails(rgb: np.ndarray, spec: tuple[int, int, int, bool], rng: np.random.Generator) -> np.ndarray:
    count, width, level, dashed = spec
    image = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    w, h = image.size
    draw = ImageDraw.Draw(image)
    for _ in range(count):
        x0, x1 = rng.uniform(0, w, 2)
        steps = np.linspace(0.0, 1.0, 25)[::2] if dashed else np.array([0.0])
        for t in steps:
            t1 = t + 0.02 if dashed else 1.0
            draw.line([(x0 + (x1 - x0) * t, h * t), (x0 + (x1 - x0) * t1, h * t1)], fill=(level,) * 3, width=width)
    return np.asarray(image, dtype=np.float64)


CLOUDS = ((0.3, 60.0), (0.5, 40.0), (0.4, 120.0))
"""Partial clouds: the share of the frame they cover and their light (grey levels)."""


def clouds(rgb: np.ndarray, spec: tuple[float, float], rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``rgb`` under soft-edged clouds that dim the stars behind them by 80 % and add their light
    with its own noise (0.4 sqrt(light) grey levels); and the cover (H, W) in [0, 1]."""
    cover, light = spec
    h, w = rgb.shape[:2]
    field = ndimage.gaussian_filter(rng.normal(size=(h, w)), sigma=min(h, w) / 12)
    field = (field - field.mean()) / field.std()
    cloud = np.clip((field - np.quantile(field, 1 - cover)) / 0.5, 0, 1)
    noise = np.sqrt(light * cloud) * 0.4 * rng.normal(size=(h, w))
    return rgb * (1 - 0.8 * cloud[..., None]) + (light * cloud + noise)[..., None], cloud
