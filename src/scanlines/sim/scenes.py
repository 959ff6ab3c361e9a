"""Random indoor scenes, reproducible from a seed.

:func:`random_scene` builds a room or a corridor, places the sensor in it and fills it
with the things line extractors get wrong: doors with walls behind them, boxes,
square and round pillars, thin partitions, walls at arbitrary angles, a grazing wall
(seen at 70-84 deg incidence) and short walls (3-12 beams long). Every scene is
checked with a noise-free scan before it is returned: the grazing wall and a short
wall must be visible, or the scene is drawn again. Mixed pixels and outliers come
from the sensor's noise model when the scene is scanned (:meth:`Scene.scan`).

**Clutter scenes** (``clutter=True``, or the kinds ``"cluttered room"`` and ``"long
corridor"``) add what real buildings have on top of that: chair and table legs (groups
of four 2-5 cm squares or round legs at the corners of a 0.38-0.5 m or 0.6-1.6 m
rectangle), people (two ellipse-ish legs 10-15 cm across, 18-35 cm apart), a glass
pane in the outline that stops beams and returns nothing (a no-return region: the
room's or corridor's wall is cut and the gap closed by glass; what lies behind is not
seen), a curved wall (one outline wall replaced by an arc bulging outwards, an
``is_line=False`` polyline: no corners, no segments, and a junction with the straight
walls it meets that the truth marks as don't care) and, for the corridor, a long one
(20-40 m). A cluttered room has one door. Round legs and people are curved shapes
(like round pillars: no true corners or segments); square legs are tiny boxes whose
faces are true segments by the usual rules (most are shorter than the don't-care
thresholds). The default kinds never draw any of it: their scenes are the same as
before clutter existed.

All randomness comes from ``numpy.random.default_rng(seed)``; the same seed and
sensor give the same scene on every platform numpy supports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scanlines.sim.family import get_sensor
from scanlines.sim.noise import NoiseModel
from scanlines.sim.scene_layout import _Door, _Layout, _outline_with_doors, _transform
from scanlines.sim.sensors import SensorSpec
from scanlines.sim.simulate import SimScan, as_rng, simulate
from scanlines.sim.world import Shape, World, box, polyline, round_pillar, wall

__all__ = ["CLUTTER_KINDS", "SCENE_KINDS", "Scene", "random_scene"]

SCENE_KINDS = ("room", "corridor")
"""The kinds of scene :func:`random_scene` builds by default."""

CLUTTER_KINDS = ("cluttered room", "long corridor")
"""The clutter kinds (``random_scene(..., clutter=True)``)."""

# Long corridors: length in metres.
LONG_CORRIDOR = (20.0, 40.0)

# Incidence range of the grazing wall, and the smallest incidence that counts as grazing.
GRAZING_INCIDENCE = (math.radians(70.0), math.radians(84.0))
# Beam count range of the short walls.
SHORT_WALL_BEAMS = (3, 12)
# Largest distance the scene generator uses, as a cap on the sensor's range.
_REACH_CAP = 10.0
_ATTEMPTS = 60


@dataclass(frozen=True, eq=False)
class Scene:
    """A world and a sensor pose in it.

    Attributes
    ----------
    world:
        The world.
    pose:
        Sensor pose ``(x, y, theta)``.
    kind:
        One of :data:`SCENE_KINDS` or :data:`CLUTTER_KINDS`.
    sensor:
        The sensor the scene was laid out for (its field of view and range).
    """

    world: World
    pose: tuple[float, float, float]
    kind: str
    sensor: SensorSpec

    @property
    def shape_kinds(self) -> frozenset[str]:
        """The ``kind`` tags of the shapes in the scene."""
        return frozenset(s.kind for s in self.world.shapes)

    def scan(
        self,
        seed: int | np.random.Generator | None = None,
        *,
        noise: NoiseModel | None = None,
        sensor: str | SensorSpec | None = None,
    ) -> SimScan:
        """Simulate a scan of the scene from its pose (see :func:`~scanlines.sim.simulate`)."""
        return simulate(self.world, sensor or self.sensor, self.pose, seed=seed, noise=noise)


# --------------------------------------------------------------------------- layout


def _grazing_wall(lay: _Layout) -> Shape:
    """A wall crossing a beam at 70-84 deg incidence (a grazing wall)."""
    bearing = lay.bearing()
    d = lay.uniform(1.2, max(1.5, 0.5 * lay.reach))
    gamma = math.pi / 2 - lay.uniform(*GRAZING_INCIDENCE)  # angle between wall and beam
    direction = lay.pose[2] + bearing + (gamma if lay.rng.random() < 0.5 else -gamma)
    u = np.array([math.cos(direction), math.sin(direction)])
    hit = lay.ray_point(bearing, d)
    back, ahead = lay.uniform(0.3, 0.6) * d, lay.uniform(0.5, 1.5) * d
    return wall(hit - back * u, hit + ahead * u, kind="grazing wall")


def _short_wall(lay: _Layout) -> Shape:
    """A wall 3-12 beams long at its distance, facing the sensor within 50 deg."""
    bearing = lay.bearing()
    d = lay.uniform(0.8, max(1.0, 0.6 * lay.reach))
    beams = lay.rng.integers(SHORT_WALL_BEAMS[0], SHORT_WALL_BEAMS[1] + 1)
    incidence = lay.uniform(-math.radians(50), math.radians(50))
    length = beams * d * abs(lay.sensor.angle_increment) / math.cos(incidence)
    direction = lay.pose[2] + bearing + math.pi / 2 + incidence
    u = np.array([math.cos(direction), math.sin(direction)]) * length / 2
    hit = lay.ray_point(bearing, d)
    return wall(hit - u, hit + u, kind="short wall")


def _box(lay: _Layout, low: float, high: float, kind: str) -> Shape:
    centre = lay.random_point(0.3)
    return box(
        centre, lay.uniform(low, high), lay.uniform(low, high), lay.uniform(0, math.pi), kind=kind
    )


def _partition(lay: _Layout) -> Shape:
    centre = lay.random_point(0.5)
    length = lay.uniform(0.8, min(2.5, 0.4 * lay.reach))
    return box(centre, length, lay.uniform(0.02, 0.06), lay.uniform(0, math.pi), kind="partition")


def _round(lay: _Layout) -> Shape:
    sides = int(lay.rng.integers(24, 49))
    return round_pillar(lay.random_point(0.4), lay.uniform(0.1, 0.35), sides=sides)


def _furnish(lay: _Layout, n_boxes: int, n_pillars: int, n_round: int, n_partitions: int) -> None:
    """Place the grazing wall and short walls first, then the rest."""
    lay.place(lambda: _grazing_wall(lay))
    for _ in range(int(lay.rng.integers(1, 3))):
        lay.place(lambda: _short_wall(lay))
    for _ in range(n_boxes):
        lay.place(lambda: _box(lay, 0.3, min(1.2, 0.2 * lay.reach), "box"))
    for _ in range(n_pillars):
        lay.place(lambda: _box(lay, 0.2, 0.5, "pillar"))
    for _ in range(n_round):
        lay.place(lambda: _round(lay))
    for _ in range(n_partitions):
        lay.place(lambda: _partition(lay))


def _door_depth(rng: np.random.Generator) -> float:
    """Half the doors are openings, half closed doors in a 0.1-0.4 m niche."""
    return float(rng.uniform(0.1, 0.4)) if rng.random() < 0.5 else 0.0


def _with_an_opening(doors: list[_Door]) -> list[_Door]:
    """Make sure at least one door is an opening (a door gap with a wall behind)."""
    if doors and all(d.depth > 0 for d in doors):
        doors[0] = doors[0]._replace(depth=0.0)
    return doors


def _room_doors(vertices: np.ndarray, rng: np.random.Generator) -> list[_Door]:
    """1-3 doors, 0.8-1.0 m wide, on distinct walls long enough to hold them."""
    lengths = np.hypot(*(np.roll(vertices, -1, axis=0) - vertices).T)
    eligible = np.flatnonzero(lengths >= 1.8)
    count = min(int(rng.integers(1, 4)), len(eligible))
    doors = []
    for e in sorted(rng.choice(eligible, size=count, replace=False).tolist()):
        length, width = float(lengths[e]), float(rng.uniform(0.8, 1.0))
        start = float(rng.uniform(0.4, length - 0.4 - width))
        doors.append(_Door(e, start / length, (start + width) / length, _door_depth(rng)))
    return _with_an_opening(doors)


def _room(
    rng: np.random.Generator, sensor: SensorSpec, reach: float, clutter: bool = False
) -> _Layout:
    w, h = reach * rng.uniform(0.6, 1.5), reach * rng.uniform(0.5, 1.2)
    vertices = _chamfered_rectangle(w, h, rng)
    doors = _room_doors(vertices, rng)
    extra: list[Shape] = []
    if clutter:
        doors, extra = _room_glass_and_curve(vertices, doors[:1], rng)
    margin = rng.uniform(1.0, 2.5, size=4)
    outer = box(
        ((margin[1] - margin[0]) / 2, (margin[3] - margin[2]) / 2),
        w + margin[0] + margin[1],
        h + margin[2] + margin[3],
        kind="outer wall",
    )
    walls = [*_outline_with_doors(vertices, doors, "room wall"), *extra, outer]
    lay = _Layout(rng, sensor, reach, vertices, walls)
    p = lay.random_point(0.6)
    lay.pose = (float(p[0]), float(p[1]), float(rng.uniform(-math.pi, math.pi)))
    _furnish(lay, int(rng.integers(1, 4)), int(rng.integers(0, 3)), int(rng.integers(1, 3)), 1)
    if clutter:
        _clutter(lay, int(rng.integers(1, 4)), int(rng.integers(1, 3)))
    return lay


def _chamfered_rectangle(w: float, h: float, rng: np.random.Generator) -> np.ndarray:
    """A ``w`` x ``h`` rectangle (CCW) with 0-2 corners cut off at arbitrary angles."""
    rect = np.array([(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)])
    cut = set(rng.choice(4, size=int(rng.integers(0, 3)), replace=False).tolist())
    out = []
    for i, pt in enumerate(rect):
        if i not in cut:
            out.append(pt)
            continue
        to_prev, to_next = rect[i - 1] - pt, rect[(i + 1) % 4] - pt
        to_prev /= np.hypot(*to_prev)
        to_next /= np.hypot(*to_next)
        cut_a, cut_b = rng.uniform(0.12, 0.35, size=2) * min(w, h)
        out.extend([pt + cut_a * to_prev, pt + cut_b * to_next])
    return np.array(out)


def _corridor(
    rng: np.random.Generator, sensor: SensorSpec, reach: float, clutter: bool = False
) -> _Layout:
    length = rng.uniform(*LONG_CORRIDOR) if clutter else reach * rng.uniform(1.2, 2.5)
    width = rng.uniform(1.6, 3.0)
    vertices = np.array(
        [(0.0, -width / 2), (length, -width / 2), (length, width / 2), (0.0, width / 2)]
    )
    doors: list[_Door] = []
    for side in (0, 2):
        n = int(rng.integers(1, 3))
        slots = np.sort(rng.choice(np.array([1, 3, 5]), size=n, replace=False))
        for slot in slots:
            t0 = slot / 6 - 0.08 + rng.uniform(-0.03, 0.03)  # the door ends before 0.95
            doors.append(_Door(side, t0, t0 + rng.uniform(0.8, 1.0) / length, _door_depth(rng)))
    doors = _with_an_opening(doors)
    extra: list[Shape] = []
    if clutter:
        doors, extra = _corridor_glass_and_curve(vertices, doors, length, width, rng)
    walls = [*_outline_with_doors(vertices, doors, "corridor wall"), *extra]
    behind = rng.uniform(2.0, 4.0, size=2)
    outer = box(
        (length / 2, (behind[1] - behind[0]) / 2),
        length + 1.0,
        width + behind.sum(),
        kind="outer wall",
    )
    lay = _Layout(rng, sensor, reach, vertices, [*walls, outer])
    y = rng.uniform(-width / 2 + 0.5, width / 2 - 0.5)
    heading = rng.uniform(-math.radians(25), math.radians(25))
    lay.pose = (float(rng.uniform(0.5, 0.25 * length)), float(y), float(heading))
    _furnish(lay, 1, int(rng.integers(0, 2)), 1, 0)
    if clutter:
        _clutter(lay, 1, int(rng.integers(1, 3)))
    return lay


# --------------------------------------------------------------------------- clutter


def _arc(a: np.ndarray, b: np.ndarray, sagitta: float, points: int) -> np.ndarray:
    """Points of the circular arc from ``a`` to ``b`` bulging ``sagitta`` to the right.

    Right of ``a -> b`` is outwards for an edge of a counter-clockwise outline.
    """
    chord = b - a
    length = math.hypot(*chord)
    right = np.array([chord[1], -chord[0]]) / length
    radius = (length**2 / 4 + sagitta**2) / (2 * sagitta)
    centre = (a + b) / 2 - right * (radius - sagitta)
    start = math.atan2(*(a - centre)[::-1])
    sweep = math.remainder(math.atan2(*(b - centre)[::-1]) - start, 2 * math.pi)
    phi = start + sweep * np.linspace(0.0, 1.0, points)
    pts = centre + radius * np.column_stack((np.cos(phi), np.sin(phi)))
    pts[0], pts[-1] = a, b
    return pts


def _curved_wall(
    vertices: np.ndarray, edge: int, rng: np.random.Generator, cap: float
) -> tuple[_Door, Shape]:
    """Outline edge ``edge`` replaced by an arc: the cut, and the arc (a curved shape)."""
    a, b = vertices[edge], vertices[(edge + 1) % len(vertices)]
    sagitta = min(float(rng.uniform(0.15, 0.4)) * math.hypot(*(b - a)), cap)
    pts = _arc(a, b, sagitta, int(rng.integers(24, 41)))
    return _Door(edge, 0.0, 1.0), polyline(pts, kind="curved wall", is_line=False)


def _glass(vertices: np.ndarray, edge: int, t0: float, t1: float) -> tuple[_Door, Shape]:
    """A glass pane from ``t0`` to ``t1`` of edge ``edge``: the cut, and the pane."""
    a, b = vertices[edge], vertices[(edge + 1) % len(vertices)]
    pane = wall(a + t0 * (b - a), a + t1 * (b - a), kind="glass", returns=False)
    return _Door(edge, t0, t1), pane


def _room_glass_and_curve(
    vertices: np.ndarray, doors: list[_Door], rng: np.random.Generator
) -> tuple[list[_Door], list[Shape]]:
    """A curved wall and a glass pane on outline walls without a door (when there are)."""
    doors = _with_an_opening(doors)
    lengths = np.hypot(*(np.roll(vertices, -1, axis=0) - vertices).T)
    free = [e for e in np.flatnonzero(lengths >= 1.8).tolist() if e not in {d.edge for d in doors}]
    free = [free[i] for i in rng.permutation(len(free))]
    extra = []
    if free:
        cut, arc = _curved_wall(vertices, free.pop(), rng, cap=0.9)
        doors, extra = [*doors, cut], [arc]
    if free:
        e = free.pop()
        length = float(lengths[e])
        width = float(rng.uniform(0.8, min(2.5, length - 0.8)))
        start = float(rng.uniform(0.4, length - 0.4 - width))
        cut, pane = _glass(vertices, e, start / length, (start + width) / length)
        doors, extra = [*doors, cut], [*extra, pane]
    return doors, extra


def _corridor_glass_and_curve(
    vertices: np.ndarray,
    doors: list[_Door],
    length: float,
    width: float,
    rng: np.random.Generator,
) -> tuple[list[_Door], list[Shape]]:
    """The far end wall curved; a 1-2.5 m glass pane on a side between the door slots."""
    cut, arc = _curved_wall(vertices, 1, rng, cap=min(0.45, 0.3 * width))
    side, slot = int(rng.choice([0, 2])), int(rng.choice([2, 4]))
    half = float(rng.uniform(1.0, 2.5)) / length / 2
    pane_cut, pane = _glass(vertices, side, slot / 6 - half, slot / 6 + half)
    return [*doors, cut, pane_cut], [arc, pane]


def _rotated(points: np.ndarray, angle: float, centre: np.ndarray) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]]) + centre


def _leg_group(lay: _Layout) -> list[Shape]:
    """Four legs of a chair (0.38-0.5 m square) or a table, square or round, 2-5 cm."""
    if lay.rng.random() < 0.6:
        side = lay.uniform(0.38, 0.5)
        w, h = side, side * lay.uniform(0.9, 1.1)
    else:
        w, h = lay.uniform(0.7, 1.6), lay.uniform(0.6, 0.9)
    size, square = lay.uniform(0.02, 0.05), bool(lay.rng.random() < 0.5)
    angle, centre = lay.uniform(0, math.pi), lay.random_point(0.5)
    corners = _rotated(np.array([(-w, -h), (w, -h), (w, h), (-w, h)]) / 2, angle, centre)
    if square:
        return [box(p, size, size, angle, kind="leg") for p in corners]
    return [round_pillar(p, size / 2, sides=12, kind="leg") for p in corners]


def _person(lay: _Layout) -> list[Shape]:
    """Two ellipse-ish legs 10-15 cm across (8-12 cm deep), 18-35 cm apart."""
    centre, heading = lay.random_point(0.5), lay.uniform(-math.pi, math.pi)
    gap = lay.uniform(0.18, 0.35)
    t = 2 * math.pi * np.arange(20) / 20
    legs = []
    for side in (-1, 1):
        across, deep = lay.uniform(0.10, 0.15), lay.uniform(0.08, 0.12)
        ellipse = np.column_stack((deep / 2 * np.cos(t), across / 2 * np.sin(t)))
        offset = _rotated(np.array([[0.0, side * gap / 2]]), heading, centre)[0]
        pts = _rotated(ellipse, heading + lay.uniform(-0.3, 0.3), offset)
        legs.append(Shape(pts, closed=True, is_line=False, kind="person leg"))
    return legs


def _clutter(lay: _Layout, leg_groups: int, people: int) -> None:
    for _ in range(leg_groups):
        lay.place_group(lambda: _leg_group(lay))
    for _ in range(people):
        lay.place_group(lambda: _person(lay))


# --------------------------------------------------------------------------- checks


def _visible_features(world: World, sensor: SensorSpec, pose: tuple[float, float, float]) -> bool:
    """Noise-free check: a grazing line edge with >= 5 beams and a visible short wall."""
    sim = simulate(world, sensor, pose, noise=NoiseModel())
    truth = sim.truth
    returned = truth.true_return
    grazing = returned & (truth.incidence >= GRAZING_INCIDENCE[0]) & ~truth.on_curve
    edges, counts = np.unique(truth.edge[grazing], return_counts=True)
    short_ids = [i for i, s in enumerate(world.shapes) if s.kind == "short wall"]
    short_edges = np.flatnonzero(np.isin(world.edge_shape, short_ids))
    short_hits = np.count_nonzero(np.isin(truth.edge[returned], short_edges))
    return bool(len(edges) and counts.max() >= 5 and short_hits >= 2)


def random_scene(
    seed: int | np.random.Generator | None = None,
    sensor: str | SensorSpec = "lms_1deg",
    kind: str | None = None,
    *,
    clutter: bool = False,
) -> Scene:
    """A random room or corridor scene laid out for ``sensor``.

    Parameters
    ----------
    seed:
        Seed or generator (``numpy.random.default_rng(seed)``): the same seed and
        sensor give the same scene.
    sensor:
        Preset name or spec; the scene's size follows its range (capped at 10 m) and
        its short walls its angular step.
    kind:
        ``"room"`` or ``"corridor"``, or a clutter kind (``"cluttered room"``, ``"long
        corridor"``); ``None`` picks one of :data:`SCENE_KINDS` at random, or of
        :data:`CLUTTER_KINDS` with ``clutter``.
    clutter:
        Pick a clutter kind when ``kind`` is ``None`` (see the module docstring).

    Returns
    -------
    Scene
        The world is turned by a random angle and shifted, so walls run at arbitrary
        angles in the world frame.

    Raises
    ------
    ValueError
        For an unknown ``kind``, or when no scene with the required features could be
        drawn (not seen in practice).
    """
    rng = as_rng(seed)
    spec = get_sensor(sensor)
    known = (*SCENE_KINDS, *CLUTTER_KINDS)
    if kind is not None and kind not in known:
        raise ValueError(f"unknown scene kind {kind!r}; known: {', '.join(known)}")
    chosen = kind or str(rng.choice(CLUTTER_KINDS if clutter else SCENE_KINDS))
    cluttered = chosen in CLUTTER_KINDS
    build = _room if chosen in ("room", "cluttered room") else _corridor
    reach = min(spec.range_max, _REACH_CAP)
    for _ in range(_ATTEMPTS):
        lay = build(rng, spec, reach, cluttered)
        angle, offset = float(rng.uniform(-math.pi, math.pi)), rng.uniform(-20.0, 20.0, size=2)
        world = World(_transform(s, angle, offset) for s in [*lay.walls, *lay.obstacles])
        x, y, theta = lay.pose
        c, s = math.cos(angle), math.sin(angle)
        pose = (c * x - s * y + offset[0], s * x + c * y + offset[1], _wrap(theta + angle))
        if _visible_features(world, spec, pose):
            return Scene(world=world, pose=pose, kind=chosen, sensor=spec)
    raise ValueError("could not draw a scene with a visible grazing wall and short wall")


def _wrap(angle: float) -> float:
    return float(math.remainder(angle, 2.0 * math.pi))
