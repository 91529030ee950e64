"""Stable object ids across frames.

Why: the user says "pick it up" about the object they named a moment ago, and
recorded steps refer to ids, so an id must stay with its physical object while
it moves a little, while an arm passes over it, and while it is in a gripper.
Detections are matched to tracks by an optimal assignment (Hungarian, from
SciPy) on distance, size and colour, or on footprint overlap (a cluster that an
arm cuts in half has its centroid far from the object's but still lies on its
footprint, or on the whole object's as last published); one cluster never
feeds two tracks, and a cluster on the footprint of a known object, in its
colour, is a piece of it, not a new object. A new object must be
seen in consecutive frames before it gets an id (a one-frame flicker never
becomes an object). An object hidden behind an arm, or under an object standing on it, is kept
as long as it is hidden; an object unseen in clear view is removed after ``forget_after``
seconds, or after ``gone_frames`` frames when new objects appear elsewhere
meanwhile (the scene was rearranged or reloaded). A held object, or one only
partly seen, keeps its last confident colour, type and size; a partly seen
object is placed where it was, moved only as far as its visible part demands.
Ids are never reused.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import linear_sum_assignment

from services.perception.descriptors import Descriptor
from services.perception.support import HOLD_RADIUS, STACK_GAP, footprint_share
from shared.messages import Gripper, SimState
from shared.robot import ROBOT

ARMS = ROBOT.arms
NO_MATCH = 1e6
COVERED_SHARE = 0.5  # of an unseen object's footprint under something seen standing on it: covered by it
PIECE_SLACK = 0.01  # m two pieces of one object may span beyond its size (each sighting's extent is rounded out)
GRASP_REACH = 0.03  # m from an object's box to a tool frame whose fingers hold it


@dataclass(frozen=True)
class TrackSettings:
    max_jump: float = 0.08  # m an object may move between two frames and keep its id
    forget_after: float = 3.0  # s an unseen (not held) object is still reported
    confirm_frames: int = 2  # consecutive sightings before a new object gets an id
    hold_radius: float = HOLD_RADIUS  # m from a holding gripper's tool frame to its object
    colour_penalty: float = 0.03  # m-equivalent cost of a colour-word change
    # m-equivalent cost of a sighting with none of the object's points: of a cup and a sliver the finger's
    # mask cut off it, both near where the hand let go, the cup is the object and the sliver a piece of it
    piece_penalty: float = 0.06
    partial_share: float = 0.5  # a sighting with fewer points than this share is partial
    gone_frames: int = 3  # unseen frames in clear view, while new objects appear, before removal
    overlap_share: float = 0.5  # share of a cluster's footprint on a track's that makes it that object
    confident: float = 0.6  # a sighting at least this confident sets an object's words and size


@dataclass
class Track:
    descriptor: Descriptor
    last_seen: float
    first_seen: float
    hits: int = 1
    id: str = ""  # empty until confirmed
    held_by: str | None = None
    hold_offset: np.ndarray | None = None
    visible: bool = True
    missed: int = 0  # consecutive frames unseen in clear view
    identity: Descriptor | None = None  # last confident full sighting (the first one, until one is confident)
    near_hand: bool = False  # a gripper is at it: partly hidden by the fingers
    shown: Descriptor | None = None  # the whole object as last published

    @property
    def confirmed(self) -> bool:
        return bool(self.id)


class Tracker:
    """Keeps the object list across frames; feed it every frame's detections."""

    def __init__(self, settings: TrackSettings = TrackSettings()) -> None:
        self.settings = settings
        self.tracks: list[Track] = []
        self._next_id = 0

    def reset(self) -> None:
        """Forget every object (a new scene was loaded); ids still never come back."""
        self.tracks = []

    def update(
        self,
        detections: list[Descriptor],
        now: float,
        state: SimState | None = None,
        hidden: Callable[[np.ndarray], bool] | None = None,
    ) -> list[dict]:
        """Fold one frame's detections in; return the published object list.

        ``hidden(position)`` says whether something (an arm) blocks the
        camera's view of a position, or it lies outside the picture, so an
        unseen object there is kept.
        """
        tools = holding_tools(state)
        hands = tool_positions(state)
        self._grasp_and_release(tools)
        for track in self.tracks:
            if track.held_by is not None and track.hold_offset is not None:
                track.descriptor.position = tools[track.held_by] + track.hold_offset
                track.descriptor.box_center = track.descriptor.position.copy()
        matches, unmatched = self._match(detections)
        for track, detection in matches:
            track.near_hand = any(
                float(np.linalg.norm(detection.position - hand)) <= self.settings.hold_radius for hand in hands
            )
            self._refresh(track, detection, now)
        seen = {id(track) for track, _ in matches}
        for track in self.tracks:
            track.visible = id(track) in seen
            if track.visible or track.held_by is not None:
                track.missed = 0
            elif (hidden is not None and hidden(track.descriptor.position)) or _covered(track, detections):
                track.last_seen, track.missed = now, 0  # behind an arm or under a cup: not gone, just out of sight
            else:
                track.missed += 1
        sightings = {id(track): detection for track, detection in matches}
        fresh = [d for d in unmatched if not self._inside_held(d, tools) and not self._piece_of_known(d, sightings)]
        newest = max([now] * bool(fresh) + [t.first_seen for t in self.tracks], default=-np.inf)
        self.tracks = [t for t in self.tracks if self._keep(t, now, newest)]
        # the first sighting is what the object is until a fuller or surer one: an open box, half box and half
        # bowl to the classifier, is never a confident sighting, and without one each piece an arm leaves in
        # view would be published as the whole object
        self.tracks += [Track(d, now, now, identity=d) for d in fresh]
        for track in self.tracks:
            if not track.confirmed and track.hits >= self.settings.confirm_frames:
                track.id = f"obj{self._next_id}"
                self._next_id += 1
            track.shown = self._shown(track)
        return self.objects()

    def standing(self) -> list[Descriptor]:
        """The confirmed objects nobody holds, as last published: what may hold up a cluster seen on it."""
        return [t.shown or t.descriptor for t in self.tracks if t.confirmed and t.held_by is None]

    def objects(self) -> list[dict]:
        """The confirmed objects as ``perception/objects`` items, by id number."""
        items = []
        for track in sorted((t for t in self.tracks if t.confirmed), key=lambda t: int(t.id[3:])):
            items.append(
                {
                    "id": track.id,
                    **(track.shown or track.descriptor).as_message(),
                    "held_by": track.held_by,
                    "visible": track.visible,
                }
            )
        return items

    # -- internals ---------------------------------------------------------
    def _grasp_and_release(self, tools: dict[str, np.ndarray]) -> None:
        """A gripper that starts holding takes the nearest object; one that opens lets go."""
        for track in self.tracks:
            if track.held_by is not None and track.held_by not in tools:
                track.held_by, track.hold_offset = None, None
        for arm, tool in tools.items():
            if any(t.held_by == arm for t in self.tracks):
                continue
            # where each object was last published, not its latest raw sighting: a cup lifted off a box may have
            # left the box's last sighting as one tall cluster of both, nearer the hand than the cup's; and only
            # an object the fingers are at: the box under a cup is near the hand, but the fingers close above it
            free = [
                t
                for t in self.tracks
                if t.confirmed and t.held_by is None and _fingers_at(t.shown or t.descriptor, tool)
            ]
            if not free:
                continue
            distances = [float(np.linalg.norm((t.shown or t.descriptor).position - tool)) for t in free]
            nearest = int(np.argmin(distances))
            if distances[nearest] <= self.settings.hold_radius:
                free[nearest].held_by = arm
                free[nearest].hold_offset = free[nearest].descriptor.position - tool

    def _shown(self, track: Track) -> Descriptor:
        """What is published: held or partly seen objects keep their confident words and size.

        A partial sighting (an arm in front of the object, fingers at it) says
        only that the object covers the visible part: the object is published
        where it was last published, moved just far enough to cover that part.
        An arm reaching across a box therefore leaves it where it stands,
        whereas a box pushed or lifted past its old extent follows the push.
        Taking the visible part's centre instead would put a box up to half
        its width off, towards the hand that hides the rest.
        """
        current, known = track.descriptor, track.identity
        if known is None or known is current:
            return current
        partial = self._partial(current, known, known)
        if (
            track.held_by is None
            and not track.near_hand
            and current.confidence >= self.settings.confident
            and not partial
        ):
            return current
        shown = replace(
            current,
            color=known.color,
            type=known.type,
            size=known.size.copy(),
            box_size=known.box_size.copy(),
            volume=known.volume,
            rgb=known.rgb,
            confidence=max(current.confidence, known.confidence),
        )
        if partial and track.held_by is None:
            last = track.shown if track.shown is not None else known
            shift = covering_shift(last.position, known.size, current.position, current.size)
            # an object nobody holds neither rises nor sinks: a box with a cup standing on it shows only its sides,
            # and a cluster that took in the cup's foot would otherwise lift the box up into the cup
            shift[2] = 0.0
            shown = replace(
                shown, position=last.position + shift, box_center=last.box_center + shift, box_yaw=last.box_yaw
            )
        return shown

    def _match(self, detections: list[Descriptor]) -> tuple[list[tuple[Track, Descriptor]], list[Descriptor]]:
        if not self.tracks or not detections:
            return [], list(detections)
        s = self.settings
        cost = np.full((len(self.tracks), len(detections)), NO_MATCH)
        for i, track in enumerate(self.tracks):
            gate = s.hold_radius if track.held_by else s.max_jump
            views = _views(track)
            for j, det in enumerate(detections):
                distance = min(float(np.linalg.norm(view.position - det.position)) for view in views)
                if track.held_by is None and not self._could_be_part_of(det, track):
                    continue
                on_footprint = (
                    track.held_by is None and max(footprint_share(det, view) for view in views) >= s.overlap_share
                )
                if distance > gate and not on_footprint:
                    continue
                whole = track.identity or track.descriptor
                cost[i, j] = (
                    distance
                    + 0.5 * float(np.linalg.norm(track.descriptor.size - det.size))
                    + (s.colour_penalty if track.descriptor.color != det.color else 0.0)
                    + s.piece_penalty * max(0.0, 1.0 - det.points / max(whole.points, 1))
                )
        rows, cols = linear_sum_assignment(cost)
        pairs = [(self.tracks[r], detections[c]) for r, c in zip(rows, cols) if cost[r, c] < NO_MATCH]
        taken = {c for r, c in zip(rows, cols) if cost[r, c] < NO_MATCH}
        return pairs, [d for j, d in enumerate(detections) if j not in taken]

    def _refresh(self, track: Track, detection: Descriptor, now: float) -> None:
        """Take the new sighting unless it is only part of the object (occluded, or in a gripper)."""
        track.last_seen = now
        track.hits += 1
        if track.held_by is not None:
            return
        known = track.identity
        partial = self._partial(detection, track.descriptor, known or track.descriptor)
        moved = float(np.linalg.norm(track.descriptor.position - detection.position))
        if partial and moved < 0.02:
            return
        track.descriptor = detection
        if (
            not track.near_hand
            and not detection.clipped
            and not self._partial(detection, detection, known or detection)
            and (self._sure(detection) or known is None or not self._sure(known))
            and (
                known is None
                or detection.points >= self.settings.partial_share * known.points
                or (moved >= self.settings.max_jump and not self._on_known_footprint(detection, track, known))
            )
        ):
            track.identity = detection

    def _sure(self, sighting: Descriptor) -> bool:
        """Whether a sighting is confident enough to set an object's words and size for good."""
        return sighting.confidence >= self.settings.confident

    def _on_known_footprint(self, detection: Descriptor, track: Track, known: Descriptor) -> bool:
        """Whether a small sighting lies on the whole object as last published: a piece of it, not the object moved.

        An arm reaching across an open box leaves a corner in view, its
        centroid a hand's width from the box's centre: taken for the box
        itself, it would make the box a 4 cm "cup" in that corner.
        """
        whole = replace(known, position=(track.shown or known).position)
        return footprint_share(detection, whole) >= self.settings.overlap_share

    def _partial(self, sighting: Descriptor, last: Descriptor, whole: Descriptor) -> bool:
        """The sighting is not the object alone: cut by the picture's edge, with under half of ``last``'s points,
        under half of ``whole``'s height (a box whose sides an arm hides shows only its top face), or half as tall
        again (a box merged with the cup on it, when the hand above hides the cup's colour)."""
        share = self.settings.partial_share
        return (
            sighting.clipped
            or sighting.points < share * last.points
            or not share * whole.size[2] <= sighting.size[2] <= (1 + share) * whole.size[2]
        )

    def _seen_elsewhere(self, track: Track) -> bool:
        """Whether a visible track of the same colour and type covers most of this unseen track's footprint.

        Two tracks of one object arise when a piece of it, cut off by an
        arm, was taken for an object of its own; while that piece is hidden
        it would be kept for ever, a phantom plate beside the real one that
        leaves no free spot on the table near it.
        """
        whole = track.shown or track.descriptor
        return any(
            other is not track
            and other.visible
            and other.confirmed
            and other.held_by is None
            and (other.shown or other.descriptor).color == whole.color
            and (other.shown or other.descriptor).type == whole.type
            and footprint_share(whole, other.shown or other.descriptor) >= self.settings.overlap_share
            and _level_with(whole, other.shown or other.descriptor)  # not one of two alike boxes stacked
            for other in self.tracks
        )

    def _piece_of_known(self, detection: Descriptor, sightings: dict[int, Descriptor]) -> bool:
        """A cluster lying on a known object's footprint is part of it (cut by an arm), not a new object.

        The footprint of its last whole sighting counts too: once an arm has
        cut a big box in two, the track follows one piece, and the other
        piece lies on the box but not on that piece. So does a cluster that,
        beside the piece the track was matched to in this frame (``sightings``,
        by id of track), spans no more than the whole
        object: a cup just let go is cut in two by the finger between them,
        and where the hand held it is a centimetre or two from where it stands.
        """
        share = self.settings.overlap_share
        return any(
            t.confirmed
            and t.held_by is None
            and self._could_be_part_of(detection, t)
            and (
                any(footprint_share(detection, view) >= share for view in (*_views(t), t.identity) if view is not None)
                or (id(t) in sightings and _completes(detection, sightings[id(t)], t.identity or t.descriptor))
            )
            for t in self.tracks
        )

    def _could_be_part_of(self, detection: Descriptor, track: Track) -> bool:
        """An arm hides part of an object but does not change its colour.

        A cluster much smaller than the object and confidently of another
        colour word is another object where it stood (the old one was taken
        away, or the scene changed), however well it lies on its footprint.
        A cluster too small to be sure of its colour may be a piece; one as
        big as the object may be the object with its colour word flickering
        between two neighbours.
        """
        known = track.identity or track.descriptor
        return (
            detection.color == known.color
            or detection.confidence < self.settings.confident
            or detection.points >= self.settings.partial_share * known.points
        )

    def _inside_held(self, detection: Descriptor, tools: dict[str, np.ndarray]) -> bool:
        """A blob at a holding gripper is the held object's visible part, not a new object."""
        return any(
            float(np.linalg.norm(detection.position - tool)) <= self.settings.hold_radius for tool in tools.values()
        )

    def _keep(self, track: Track, now: float, newest: float) -> bool:
        """Whether a track stays; ``newest`` is when the most recent object first appeared."""
        if track.visible or track.held_by is not None:
            return True
        if not track.confirmed:
            return False  # a candidate must be seen in consecutive frames
        if self._seen_elsewhere(track):
            return False  # an object seen now in full is this one: the unseen track was a second sighting of it
        if track.missed >= self.settings.gone_frames and newest > track.last_seen:
            return False  # plainly absent while new objects appeared: it moved, or the scene changed
        return now - track.last_seen <= self.settings.forget_after


def _fingers_at(obj: Descriptor, tool: np.ndarray) -> bool:
    """Whether a closed gripper's tool frame lies within ``GRASP_REACH`` of the object's box."""
    outside = np.maximum(np.abs(tool - obj.position) - obj.size / 2, 0.0)
    return float(np.linalg.norm(outside)) <= GRASP_REACH


def _completes(piece: Descriptor, sighting: Descriptor, whole: Descriptor) -> bool:
    """Whether ``piece`` and ``sighting`` side by side, level, span no more than ``whole`` (plus ``PIECE_SLACK``).

    Only a piece of the whole's colour: a cup just lifted off a box is
    another object beside the box's sighting, not a piece of the box.
    """
    if piece.points >= whole.points or piece.color != whole.color or not _level_with(piece, sighting):
        return False
    lo = np.minimum(piece.position[:2] - piece.size[:2] / 2, sighting.position[:2] - sighting.size[:2] / 2)
    hi = np.maximum(piece.position[:2] + piece.size[:2] / 2, sighting.position[:2] + sighting.size[:2] / 2)
    return bool(np.all(np.sort(hi - lo) <= np.sort(whole.size[:2]) + PIECE_SLACK))


def _level_with(a: Descriptor, b: Descriptor) -> bool:
    """Whether two objects' centres are less than half the taller one's height apart in height."""
    return abs(float(a.position[2] - b.position[2])) < max(float(a.size[2]), float(b.size[2])) / 2


def _covered(track: Track, detections: list[Descriptor]) -> bool:
    """Whether something seen now stands on the track's object and covers it from the camera.

    A box with a cup just put on it can show nothing of itself: the cup
    covers its lid and the hand above the cup its sides. It is still there.
    """
    whole = track.shown or track.descriptor
    top = whole.position[2] + whole.size[2] / 2
    return any(
        d.position[2] - d.size[2] / 2 >= top - STACK_GAP and footprint_share(whole, d) >= COVERED_SHARE
        for d in detections
    )


def _views(track: Track) -> tuple[Descriptor, ...]:
    """Where a track's object may be: its last sighting and the whole object as last published.

    The last sighting alone is not enough: while an arm sweeps over a plate,
    the track follows one visible piece after another, and the next piece,
    on the far side of the plate, lies neither near that piece nor on it;
    it does lie on the whole plate.
    """
    return (
        (track.descriptor,)
        if track.shown is None or track.shown is track.descriptor
        else (track.descriptor, track.shown)
    )


def holding_tools(state: SimState | None) -> dict[str, np.ndarray]:
    """Tool-frame positions of the grippers holding something: fingers kept apart while they squeeze."""
    if state is None:
        return {}
    tools = {}
    for arm in ARMS:
        gripper = state.grippers.get(arm)
        if gripper is not None and _holding(gripper) and arm in state.ee:
            position = np.asarray(state.ee[arm][:3], dtype=float)
            if np.isfinite(position).all():
                tools[arm] = position
    return tools


def _holding(gripper: Gripper) -> bool:
    width, effort = gripper.width, gripper.effort
    if effort is None or not np.isfinite(width) or not np.isfinite(effort):
        return False
    return ROBOT.gripper.state(width, effort) == "holding"


def tool_positions(state: SimState | None) -> list[np.ndarray]:
    """Tool-frame positions of both grippers, holding or not."""
    positions = []
    for pose in (state.ee if state is not None else {}).values():
        position = np.asarray(pose[:3], dtype=float)
        if np.isfinite(position).all():
            positions.append(position)
    return positions


def covering_shift(center: np.ndarray, size: np.ndarray, part_center: np.ndarray, part_size: np.ndarray) -> np.ndarray:
    """The smallest move of the box (``center``, ``size``) after which it covers the box of a part.

    Along an axis where the part is longer than the whole (a cluster that
    took in something else), the whole is centred on the part instead.
    """
    low, high = center - size / 2, center + size / 2
    part_low, part_high = part_center - part_size / 2, part_center + part_size / 2
    shift = np.clip(part_high - high, 0.0, None) - np.clip(low - part_low, 0.0, None)
    longer = part_size > size
    shift[longer] = (part_center - center)[longer]
    return shift
