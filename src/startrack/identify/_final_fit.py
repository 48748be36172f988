"""The last stage of every lost-in-space solve: fit the verified candidate to all stars.

A matcher verifies a candidate on the few stars of its pattern and their neighbours. This module
fits the attitude (and the focal length when it is not known) to the matched stars, re-matches
every image star to the catalog stars the fit predicts, and repeats until the matches settle
(Huffman 2006 §5.5.4: the identification is confirmed and refined on all stars in the field).

A candidate can carry a wrong association or two (a false star that happened to fall within
the verification radius, or a real star paired with a neighbour). With a free focal length and a
handful of stars, the least-squares fit bends to it: the residuals of the right stars grow as
much as the wrong one's, and the bent solution no longer predicts the rest of the field, so the
re-match cannot add the stars that would expose it. :func:`settle_matches` therefore asks of
every matched star where the fit to the *other* stars puts it (its deleted residual,
:func:`.refine.leave_one_out_residuals`); a star that those would not have matched (farther than
:data:`REMATCH_RADIUS_PX`) is dropped and the fit settled again, up to :data:`MAX_LEFT_OUT` times.

A solve runs this stage once, on a few dozen stars, so its cost is per-call overhead: the fits
work on rotation matrices (:func:`.refine.fit_pose`), the re-match is one compiled call
(:func:`.refine.match_predicted`) over the catalog stars of the cone that holds the image, chosen
once by one compiled scan of the field's brightest stars and kept while the pose moves less than a
margin (:class:`_Catalog`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ._candidate import Candidate
from ._field_stars import FieldStars
from ._refine import fit_pose, leave_one_out_residuals, match_predicted, pixel_vectors, stars_in_cone
from ._verify import bands_of, match_nearest

MAX_REFINE_ROUNDS = 12
"""Fit / re-match rounds after verification, at most. Most candidates settle in two (the second
changes nothing). A wide lens that nobody calibrated takes more: each round matches the stars
within :data:`REMATCH_RADIUS_PX` of where the last fit puts them, and the fit reaches the bent
corners a band of stars at a time. With 4 rounds, simulated images of 80-89 deg fields with k1
of -0.15 to -0.2 (lenses whose polynomial folds back inside the image) stopped at a lens that left
their corners out (k1 off by 0.02-0.03, median residual 0.45-0.65 px against 0.14-0.19 px through
the true lens). Lenses that do not fold settled on the same lens before as now (star lists of
70-89 deg lenses with k1 of -0.10 to -0.2)."""

REMATCH_RADIUS_PX = 3.0
"""After verification, every image star within this distance of a predicted star is matched."""

MIN_STARS_FOR_K1 = 12
K1_FOCAL_SPAN = 0.1
"""When the focal length is searched over a range wider than 10 % (an uncalibrated camera), the
final fit also estimates the radial distortion k1 if at least MIN_STARS_FOR_K1 stars are
matched: the lenses of photographs are rarely calibrated. A ``fov_deg`` (+-3 %) fits the focal
length only, unless the field is wide (:data:`WIDE_FOV_DEG`)."""

WIDE_FOV_DEG = 40.0
MIN_STARS_FOR_K2 = 30
"""A lens that is not calibrated and spans at least WIDE_FOV_DEG along its long side (a phone, a
webcam, a wide lens; a portrait image as a landscape one) is fitted with k1 at every round of the
re-match, not only at the end (its far side is bent by tens of pixels, beyond the re-match radius
of a pinhole fit), and then settled again with k2 as well once MIN_STARS_FOR_K2 stars are matched.
Freed from the first round, k2 let the fit bend to the stars matched so far and keep the rest
out: on a simulated 1920 x 1080 image of 81.8 deg with k1 = -0.154 (its polynomial folds back at
the corners), the fit settled on k1 = -0.185, k2 = +0.046 with 1,068 stars (median residual
0.65 px); in two steps, on k1 = -0.154, k2 = 0.000 with 1,379 (0.17 px)."""

MIN_STARS_FOR_ASPECT = 6
"""The pixel aspect (fy / fx), when not known, is fitted once this many stars are matched: from
the first round, since 3 % of aspect moves the edge of a 1024 px image by 15 px, beyond the
re-match radius of a fit that holds the aspect fixed."""

DEPTH_FACTOR = 5.0
"""The re-match considers only the catalog stars that are bright enough for the image: the
brightest DEPTH_FACTOR times as many as there are image stars in the field's solid angle (all
of them for a narrow field). In a wide field a 3 px radius covers a tenth of a square degree,
and the whole catalog to V 9.5 would put a faint star within reach of every false detection."""

BLEND_PX = 0.5
"""Catalog stars closer than this (pixels) to a brighter catalog star are not matched separately."""

SETTLED_PX = 0.05
"""Once a re-fit moves no star by more than this, re-matching cannot change the matches (bar a
star within 0.05 px of the re-match radius) and the loop stops."""

MAX_LEFT_OUT = 3
"""Wrong associations removed one at a time, at most this many (a candidate verified with a false
match probability below 1e-6 rarely carries more)."""

MIN_STARS_TO_CHECK = 5
"""Leaving one star out needs enough stars left to fit attitude and focal length and to judge."""


@dataclass(frozen=True)
class FinalFit:
    """The settled fit: attitude (rotation matrix (3, 3) taking ICRS to camera vectors), camera,
    matched image indices (K,), their catalog rows (K,), the rows' ICRS unit vectors (K, 3) at the
    solve epoch and the pixel residuals (K,)."""

    matrix_cam_from_icrs: NDArray[np.float64]
    camera: Camera
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    ref_icrs: NDArray[np.float64]
    residual_px: NDArray[np.float64]

    @cached_property
    def rot_cam_from_icrs(self) -> Rotation:
        """The attitude as a Rotation."""
        return Rotation.from_matrix(self.matrix_cam_from_icrs)


SELECT_MARGIN_PX = 8.0
"""The re-match looks at the catalog stars within REMATCH_RADIUS_PX + SELECT_MARGIN_PX of an image
star at the pose they were chosen for; once a fit moves some image point farther than the margin
from that pose, they are chosen again (:class:`_Catalog`)."""

ANGLE_PER_PIXEL_SAFETY = 1.25
"""A pixel spans at most 1 / f radians of a pinhole camera anywhere in its image (the gnomonic
projection only magnifies off axis); the choice of catalog stars allows a local scale up to 1.25
times that, for the distortion of an uncalibrated lens."""


@dataclass(frozen=True)
class _Field:
    """What stays fixed while a candidate settles: image stars (N,) px, the catalog stars at the
    solve epoch, which camera parameters are free at every round (focal length, pixel aspect,
    k1, k2; each also needs enough matched stars, :func:`_free`) and how many of the catalog
    stars (brightest first) a re-match may use (:func:`depth_limit`)."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    stars: FieldStars
    fit_focal: bool
    fit_aspect: bool = False
    fit_k1: bool = False
    fit_k2: bool = False
    depth: int | None = None


def _free(field: _Field, n_stars: int) -> dict[str, bool]:
    """Keyword flags of :func:`.refine.fit_pose` for a fit of ``n_stars`` stars of this field."""
    return {"fit_focal": field.fit_focal, "fit_aspect": field.fit_aspect and n_stars >= MIN_STARS_FOR_ASPECT,
            "fit_k1": field.fit_k1 and n_stars >= MIN_STARS_FOR_K1,
            "fit_k2": field.fit_k2 and n_stars >= MIN_STARS_FOR_K2}


def lens_folds(camera: Camera, x: NDArray, y: NDArray) -> bool:
    """Whether the camera's lens model cannot be inverted at some of the image points ``x``,
    ``y`` (pixels, (N,)): its distortion folds back before them, so they map to no direction. A
    fit to the stars of a wide lens can reach such a model where it has no stars; it is then
    refitted with fewer terms."""
    return not bool(np.all(np.isfinite(pixel_vectors(camera, x, y))))


def _fit_lens(field: _Field, matrix: NDArray, camera: Camera, ref: NDArray, img: NDArray):
    """:func:`.refine.fit_pose` with the field's free parameters for ``img.size`` stars, dropping
    k2 and then k1 when the fitted lens folds (:func:`lens_folds`): (matrix, camera, residual_px)."""
    free = _free(field, img.size)
    x, y = field.x[img], field.y[img]
    for drop in ((), ("fit_k2",), ("fit_k2", "fit_k1")):
        flags = {**free, **{key: False for key in drop}}
        fitted = fit_pose(matrix, camera, ref, x, y, **flags)
        if not (flags["fit_k1"] or flags["fit_k2"]) or not lens_folds(fitted[1], field.x, field.y):
            return fitted
    return fitted


def field_solid_angle_sr(camera: Camera) -> float:
    """Solid angle (sr) of the pinhole image rectangle: 4 asin(sin(a / 2) sin(b / 2)) for full
    angular width a and height b."""
    half_w = math.atan(camera.width / (2.0 * camera.fx))
    half_h = math.atan(camera.height / (2.0 * camera.fy))
    return 4.0 * math.asin(math.sin(half_w) * math.sin(half_h))


def depth_limit(n_image_stars: int, camera: Camera, n_catalog: int) -> int:
    """How many of the catalog's stars (brightest first, all-sky) the re-match may use: those
    brighter than the magnitude at which the field holds :data:`DEPTH_FACTOR` times
    ``n_image_stars`` of them on average (at most ``n_catalog``)."""
    share = field_solid_angle_sr(camera) / (4.0 * math.pi)
    return int(min(n_catalog, math.ceil(DEPTH_FACTOR * max(n_image_stars, 1) / share)))

@dataclass(frozen=True)
class _Catalog:
    """The catalog stars a re-match considers: rows (S,) and ICRS unit vectors (S, 3) of those
    within reach of an image star at the pose (attitude matrix (3, 3), camera) they were chosen for.

    A catalog star that some pose within :data:`SELECT_MARGIN_PX` of that one matches (within
    :data:`REMATCH_RADIUS_PX`) is among them, so a re-match over them equals a re-match over the
    whole catalog. Stars that the image shows blended into a brighter one (closer than
    :data:`BLEND_PX`) are left out: the spot is named after the brighter star.
    """

    matrix: NDArray[np.float64]
    camera: Camera
    rows: NDArray[np.int64]
    vectors: NDArray[np.float64]

    @classmethod
    def whole_field(cls, field: _Field, matrix: NDArray, camera: Camera) -> _Catalog:
        """Every catalog star (to the field's depth) within 1.2 times the pinhole half diagonal of
        the boresight: a selection that serves any lens bend the k1 scan tries."""
        half_diagonal = math.atan(math.hypot(camera.width / camera.fx, camera.height / camera.fy) / 2.0)
        near = np.sort(field.stars.near(matrix[2], min(1.2 * half_diagonal, math.radians(89.0))))
        return cls._kept(field, matrix, camera, near)

    @classmethod
    def chosen(cls, field: _Field, matrix: NDArray, camera: Camera) -> _Catalog:
        """The catalog stars within reach of the image stars at this pose: those (to the field's
        depth, not blended) of the cone around the boresight that holds the whole image and the
        reach (:func:`_image_reach_rad`), found by one compiled scan of the field's brightest
        stars (:func:`.refine.stars_in_cone`) or, when that would read more than
        :data:`SCAN_PER_TREE_STAR` times the stars of the cone, in the sectors and bands of z the
        cone reaches (:meth:`.verify.SkyBands.brightest_in_cone`; the same stars); for a lens
        whose corner cannot be inverted (or above :data:`CONE_SCAN_LIMIT`), those near each image star."""
        count = len(field.stars.rows) if field.depth is None else min(field.depth, len(field.stars.rows))
        reach_rad = _image_reach_rad(camera)
        if count > CONE_SCAN_LIMIT or not math.isfinite(reach_rad):
            return cls.around_stars(field, matrix, camera)
        in_cone = 0.5 * (1.0 - math.cos(min(reach_rad, math.pi))) * len(field.stars.rows)  # expected, all depths
        args = (count, matrix[2], reach_rad, field.stars.brighter_neighbour_rad, BLEND_PX / camera.fx)
        if count > SCAN_PER_TREE_STAR * in_cone:
            near = bands_of(field.stars, field.stars.vectors).brightest_in_cone(*args)
        else:
            near = stars_in_cone(field.stars.vectors, *args)
        return cls(matrix, camera, field.stars.rows[near], _rows_of(field.stars.vectors, near))

    @classmethod
    def around_stars(cls, field: _Field, matrix: NDArray, camera: Camera) -> _Catalog:
        """The catalog stars within reach of some image star at this pose."""
        directions = pixel_vectors(camera, field.x, field.y) @ matrix  # ICRS unit vectors (N, 3)
        reach_px = REMATCH_RADIUS_PX + SELECT_MARGIN_PX
        near = field.stars.around(directions, ANGLE_PER_PIXEL_SAFETY * reach_px / min(camera.fx, camera.fy))
        return cls._kept(field, matrix, camera, near)

    @classmethod
    def _kept(cls, field: _Field, matrix: NDArray, camera: Camera, near: NDArray) -> _Catalog:
        """The stars ``near`` (indices into the field's stars, sorted) within the depth and not blended."""
        if field.depth is not None:
            near = near[:np.searchsorted(near, field.depth)]  # indices are brightness ranks
        near = near[field.stars.brighter_neighbour_rad[near] >= BLEND_PX / camera.fx]
        return cls(matrix, camera, field.stars.rows[near], _rows_of(field.stars.vectors, near))

    def serves(self, matrix: NDArray, camera: Camera) -> bool:
        """Whether no image point moves more than the margin between the chosen pose and this one."""
        return _pose_shift_px(self.matrix, self.camera, matrix, camera) <= SELECT_MARGIN_PX


CONE_SCAN_LIMIT = 1_000_000
"""The catalog stars of a re-match are chosen in one cone when the field's stars to its depth are
at most this many (all of Hipparcos), else near each image star (:meth:`_Catalog.around_stars`)."""

SCAN_PER_TREE_STAR = 40.0
"""The field's brightest stars (to its depth) are scanned for a cone unless that reads more than
this many times the stars the cone holds (a narrow field, whose depth reaches faint stars); then
the sectors of longitude and bands of z the cone reaches are read instead. The brightest stars
are the same at every solve and stay in the cache; the bands are elsewhere each time (timed in a
loop of solves, the scan was the faster at FOV 20, and at FOV 10 no slower than the KD-tree this
rule chose before; ``benchmarks/lis_benchmark.py`` times whole solves)."""

CONE_PAIRS_LIMIT = 200_000
"""A re-match compares every image star with every catalog star it considers (compiled,
:func:`.refine.match_predicted`) when there are at most this many pairs; beyond, the catalog
stars are chosen near each image star and paired through KD-trees (:func:`.verify.match_nearest`)."""


def _image_reach_rad(camera: Camera) -> float:
    """Largest angle (radians) from the boresight of a direction the image shows, plus the reach
    of a re-match (REMATCH_RADIUS_PX + SELECT_MARGIN_PX, times ANGLE_PER_PIXEL_SAFETY): the angle
    of the farthest image corner (through the lens model when there is one). NaN when the lens
    model cannot invert a corner."""
    w, h = camera.width - 0.5, camera.height - 0.5
    if camera.has_distortion:
        corners = pixel_vectors(camera, np.array([-0.5, w, -0.5, w]), np.array([-0.5, -0.5, h, h]))
        corner_rad = float(np.max(np.arctan2(np.hypot(corners[:, 0], corners[:, 1]), corners[:, 2])))
    else:
        corner_rad = math.atan(max(math.hypot((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy)
                                   for u in (-0.5, w) for v in (-0.5, h)))  # atan grows: the farthest corner's
    reach_px = REMATCH_RADIUS_PX + SELECT_MARGIN_PX
    return corner_rad + ANGLE_PER_PIXEL_SAFETY * reach_px / min(camera.fx, camera.fy)


def rematch(field: _Field, catalog: _Catalog, matrix_cam_from_icrs: NDArray,
            camera: Camera) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """Match every image star to its nearest predicted catalog star (of ``catalog``) within
    :data:`REMATCH_RADIUS_PX`, for an attitude matrix (3, 3) taking ICRS to camera vectors:
    image index (K,), catalog row (K,) and the row's ICRS unit vector (K, 3). Closest pairs
    first, each star once (as :func:`.verify.match_nearest`)."""
    if field.x.size * catalog.rows.size <= CONE_PAIRS_LIMIT:
        img_i, near_i = match_predicted(catalog.vectors, matrix_cam_from_icrs, camera, field.x, field.y,
                                        REMATCH_RADIUS_PX)
    else:
        px, py = camera.vector_to_pixel(catalog.vectors @ matrix_cam_from_icrs.T)
        inside = np.flatnonzero(camera.in_image(px, py))
        img_i, cat_i = match_nearest(field.x, field.y, px[inside], py[inside], REMATCH_RADIUS_PX)
        near_i = inside[cat_i]
    return img_i, catalog.rows[near_i], _rows_of(catalog.vectors, near_i)


def _rows_of(vectors: NDArray, index: NDArray) -> NDArray:
    """``vectors[index]`` for vectors (S, 3) and indices (K,): ``np.take`` along axis 0, several
    times cheaper than fancy indexing for the thousands of stars of a cone."""
    return np.take(vectors, index, axis=0)


def _turn_rad(matrix_a: NDArray, matrix_b: NDArray) -> float:
    """Angle (radians) of the rotation between two attitude matrices (3, 3): atan2 of the sine
    (from the antisymmetric part of ``A B^T``) and the cosine (from its trace), precise at any angle."""
    (d00, d01, d02), (d10, d11, d12), (d20, d21, d22) = (matrix_a @ matrix_b.T).tolist()
    return math.atan2(0.5 * math.hypot(d21 - d12, d02 - d20, d10 - d01), 0.5 * (d00 + d11 + d22 - 1.0))


def _pose_shift_px(matrix_a: NDArray, cam_a: Camera, matrix_b: NDArray, cam_b: Camera) -> float:
    """Largest shift (pixels) of an image point between two attitudes (matrices (3, 3)) and
    cameras (focal lengths, pixel aspect, k1, k2)."""
    half_diagonal_px = 0.5 * math.hypot(cam_a.width, cam_a.height)
    focal_change = abs(cam_a.fx / cam_b.fx - 1.0) + abs(cam_a.fy / cam_b.fy - 1.0)
    reach2 = (half_diagonal_px / min(cam_b.fx, cam_b.fy)) ** 2  # squared pinhole radius of the corner
    bend = abs(cam_a.k1 - cam_b.k1) * reach2 + abs(cam_a.k2 - cam_b.k2) * reach2**2
    turn = _turn_rad(matrix_a, matrix_b)
    return turn * cam_b.fx * (1.0 + (half_diagonal_px / cam_b.fx) ** 2) + (focal_change + bend) * half_diagonal_px


def _settle(field: _Field, matrix: NDArray, camera: Camera, img: NDArray, rows: NDArray, ref: NDArray,
            catalog: _Catalog | None) -> tuple[FinalFit, _Catalog | None]:
    """Fit, re-match all stars, and repeat until the matches (or the pose) stop changing.
    ``ref`` (K, 3) are the ICRS unit vectors of the catalog rows (K,) matched to the image stars (K,).
    Returns the fit and the catalog stars of the last re-match (chosen anew when the pose has
    moved beyond the margin of ``catalog``, or when it is None)."""
    for round_ in range(MAX_REFINE_ROUNDS):
        before = (matrix, camera)
        matrix, camera, res = _fit_lens(field, matrix, camera, ref, img)
        if round_ == MAX_REFINE_ROUNDS - 1 or (round_ > 0 and _pose_shift_px(*before, matrix, camera) < SETTLED_PX):
            break
        if catalog is None or not catalog.serves(matrix, camera):
            catalog = _Catalog.chosen(field, matrix, camera)
        new_img, new_rows, new_ref = rematch(field, catalog, matrix, camera)
        unchanged = new_img.size == img.size and bool((new_img == img).all() and (new_rows == rows).all())
        if unchanged or new_img.size < img.size:
            break
        img, rows, ref = new_img, new_rows, new_ref
    return FinalFit(matrix, camera, img, rows, ref, res), catalog


K1_SCAN = np.linspace(-0.3, 0.3, 25)
"""Radial distortions k1 tried on a wide field's candidate before it settles (:func:`_scan_k1`),
in steps of 0.025: each moves the corner of a 90 deg field by about 2 % of its radius from the
next, inside the re-match radius of a fit that then frees k1."""

K1_SCAN_REACH2 = 2.0 * math.tan(math.radians(50.0)) ** 2
"""The squared pinhole radius (2.84) of a square 100 deg field's corner, the widest of the default
search. A wider field's scan is :data:`K1_SCAN` scaled by this over its own corner's: the same
steps of the corner's displacement. Unscaled, the steps of 0.025 moved the corner of a 120 deg
3:2 field by 11 % of its radius, of a 150 deg one by 50 %, and 2 of 10 simulated 150 deg frames
(k1 = -0.005) settled on a lens that left their corners 2-62 px off; scaled, none of 80 (two seeds,
both modes of ``benchmarks/realdata_benchmark.py --wide``)."""


def _scan_k1(field: _Field, matrix: NDArray, camera: Camera, img: NDArray,
             ref: NDArray) -> tuple[NDArray, Camera, tuple[NDArray, NDArray, NDArray]]:
    """The k1 of :data:`K1_SCAN` under which the candidate's stars (image indices ``img``, ICRS
    vectors ``ref``), refitted, re-match the most image stars: (attitude matrix, camera, and
    the re-match (image index, catalog row, ICRS vector)). A wide lens bends its far side by
    tens of pixels, so a candidate verified near the centre with a pinhole fit re-matches only
    there, too few stars to fit k1 from; the scan finds the bend first (smallest |k1| on a tie).
    A k1 whose lens folds before some of the image's stars is passed over: beyond 100 deg the
    scan's strongest barrels fold inside the frame (k1 = -0.3 folds 47 deg off axis)."""
    catalog = _Catalog.whole_field(field, matrix, camera)
    reach2 = (camera.width / (2.0 * camera.fx)) ** 2 + (camera.height / (2.0 * camera.fy)) ** 2
    if reach2 > K1_SCAN_REACH2:
        img, ref = _without_refit_outliers(field, matrix, camera, img, ref)
    best = (-1, matrix, camera, (img, np.zeros(0, np.int64), ref))
    for k1 in K1_SCAN[np.argsort(np.abs(K1_SCAN), kind="stable")] * min(1.0, K1_SCAN_REACH2 / reach2):
        trial = camera.with_distortion(k1=float(k1), k2=0.0)
        if lens_folds(trial, field.x, field.y):  # no lens: stars of the frame beyond its fold
            continue
        m, trial, _ = fit_pose(matrix, trial, ref, field.x[img], field.y[img], fit_focal=field.fit_focal)
        found = rematch(field, catalog, m, trial)
        if found[0].size > best[0]:
            best = (found[0].size, m, trial, found)
    return best[1], best[2], best[3]


REFIT_OUTLIER_PX = 5.0
"""Before the k1 scan of a field wider than the default search's (:data:`K1_SCAN_REACH2`), a
candidate's star that a fit of its other stars puts farther than this (pixels) from its
detection is dropped, worst first, at most :data:`MAX_LEFT_OUT` (:func:`_without_refit_outliers`).
Such a candidate is verified on part of the frame, where the attitude's tilt and the focal length
trade: one of a 135 deg frame held 6 stars, one of them 22 px from where the true attitude puts
its catalog star (21.5 px by this refit; the others 2.3-6.1 px), and the solution settled 0.6 deg
off, its focal length 2.6 % long, 151 of its 529 matches chance pairs. On
``benchmarks/realdata_benchmark.py --wide``'s frames (seeds 1-3, field given and searched, 480
frames) 478 solved within 2 px with it, 475 without."""


def _without_refit_outliers(field: _Field, matrix: NDArray, camera: Camera, img: NDArray,
                            ref: NDArray) -> tuple[NDArray, NDArray]:
    """The candidate's image indices ``img`` (K,) and ICRS vectors ``ref`` (K, 3) without the stars
    beyond :data:`REFIT_OUTLIER_PX` of :func:`_refit_residuals`, worst first."""
    for _ in range(MAX_LEFT_OUT):
        if img.size <= MIN_STARS_TO_CHECK:
            break
        residual = _refit_residuals(field, matrix, camera, img, ref)
        worst = int(np.argmax(residual))
        if residual[worst] <= REFIT_OUTLIER_PX:
            break
        keep = np.arange(img.size) != worst
        img, ref = img[keep], ref[keep]
    return img, ref


def _refit_residuals(field: _Field, matrix: NDArray, camera: Camera, img: NDArray, ref: NDArray) -> NDArray:
    """How far (pixels, (K,)) the fit of the other stars (attitude, and the focal length when the
    field frees it; ``camera``'s lens) puts each of the stars ``img`` from its detection, refitted
    star by star: :func:`.refine.leave_one_out_residuals` linearises, and understates a star that
    alone holds one side of the frame. inf where the others' fit maps it to no pixel."""
    out = np.empty(img.size)
    for i in range(img.size):
        keep = np.arange(img.size) != i
        fitted, cam, _ = fit_pose(matrix, camera, ref[keep], field.x[img[keep]], field.y[img[keep]],
                                  fit_focal=field.fit_focal)
        px, py = cam.vector_to_pixel(ref[i] @ fitted.T)
        out[i] = math.hypot(float(px) - field.x[img[i]], float(py) - field.y[img[i]])
    return np.where(np.isnan(out), np.inf, out)


def _without_worst(field: _Field, fit: FinalFit, catalog: _Catalog | None) -> tuple[FinalFit, _Catalog | None] | None:
    """The fit settled again (as :func:`_settle`) without the star the others' fit puts farthest
    from its match, if that is beyond the re-match radius (the others would not have matched it);
    else None."""
    img = fit.image_index
    free = _free(field, img.size)
    deleted = leave_one_out_residuals(fit.matrix_cam_from_icrs, fit.camera, fit.ref_icrs, field.x[img],
                                      field.y[img], fit_focal=free["fit_focal"], fit_aspect=free["fit_aspect"])
    deleted = np.where(np.isfinite(deleted), deleted, 0.0)  # a star the fit cannot do without is kept
    worst = int(np.argmax(deleted))
    if deleted[worst] <= REMATCH_RADIUS_PX:
        return None
    keep = np.arange(img.size) != worst
    return _settle(field, fit.matrix_cam_from_icrs, fit.camera, img[keep], fit.catalog_rows[keep],
                   fit.ref_icrs[keep], catalog)


def settle_matches(x: NDArray, y: NDArray, stars: FieldStars, cand: Candidate,
                   focal_range: tuple[float, float] | None, *, fit_aspect: bool = False) -> FinalFit:
    """Fit a verified candidate to every star it explains, dropping a wrong association.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Image stars (pixels, brightest first), as the matcher saw them.
    stars : FieldStars
        Catalog stars at the solve epoch.
    cand : Candidate
        The matcher's verified candidate.
    focal_range : (float, float) or None
        Focal lengths searched (pixels), or None when the camera is calibrated (focal length
        fixed). The focal length is fitted when a range is given; k1 as well when the range is
        wider than :data:`K1_FOCAL_SPAN` or the field wide (:data:`WIDE_FOV_DEG`), and at least
        :data:`MIN_STARS_FOR_K1` stars match (k2 too in a wide field, from
        :data:`MIN_STARS_FOR_K2` stars).
    fit_aspect : bool
        Fit the pixel aspect fy / fx too (it is not known), from :data:`MIN_STARS_FOR_ASPECT` stars.

    Returns
    -------
    FinalFit
    """
    fit_focal = focal_range is not None
    wide = fit_focal and cand.camera.fov_long_deg >= WIDE_FOV_DEG
    fit_k1 = wide or (focal_range is not None
                      and (focal_range[1] > focal_range[0] * (1 + K1_FOCAL_SPAN) or cand.camera.k1 != 0))
    field = _Field(x, y, stars, fit_focal, fit_aspect and fit_focal, wide, wide,
                   depth_limit(len(x), cand.camera, len(stars.rows)))
    matrix, camera, img, rows = cand.matrix_cam_from_icrs, cand.camera, cand.image_index, cand.catalog_rows
    ref = stars.vectors_of(rows)
    catalog = None
    if wide:  # k1 alone first, then k2 too (MIN_STARS_FOR_K2)
        matrix, camera, (img, rows, ref) = _scan_k1(field, matrix, camera, img, ref)
        k1_only, catalog = _settle(replace(field, fit_k2=False), matrix, camera, img, rows, ref, None)
        matrix, camera, img, rows, ref = (k1_only.matrix_cam_from_icrs, k1_only.camera, k1_only.image_index,
                                          k1_only.catalog_rows, k1_only.ref_icrs)
    fit, catalog = _settle(field, matrix, camera, img, rows, ref, catalog)
    for _ in range(MAX_LEFT_OUT):
        better = _without_worst(field, fit, catalog) if fit.image_index.size >= MIN_STARS_TO_CHECK else None
        if better is None:
            break
        fit, catalog = better
    if fit_k1 and not wide and fit.image_index.size >= MIN_STARS_FOR_K1:  # lens distortion last, settled matches
        img = fit.image_index
        matrix, camera, res = fit_pose(fit.matrix_cam_from_icrs, fit.camera, fit.ref_icrs, x[img], y[img],
                                       **{**_free(field, img.size), "fit_k1": True})
        if not lens_folds(camera, x, y):
            fit = FinalFit(matrix, camera, img, fit.catalog_rows, fit.ref_icrs, res)
    return fit
