"""The simulator service: the physics loop at real time, its streams and its control queryables.

Why this shape: SAPIEN must be driven from one thread, so the main thread
owns the world and runs a loop that (1) applies commands queued by the
request handlers, (2) steps physics, (3) publishes state and ground truth
(and at once when stopped joints come to rest), and (4) renders the head
camera at the cloud rate. The renderer draws on its own threads while the
loop goes on; the loop reads the frame when it should be done
(:mod:`services.sim.render_time`), so a stop never waits behind a frame.
Turning a frame into a cloud and encoding the multi-megabyte message happen
on a separate thread, so publishing never stalls physics. Pacing holds simulated time to wall
time (times ``--speed``); when rendering falls behind, physics catches up
in a burst and the published ``rtf`` says how well it keeps up.
"""

from __future__ import annotations

import argparse
import logging
import queue
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

import cv2
import numpy as np

from services.sim import control
from services.sim.cloud import cloud_message
from services.sim.motion import TORSO_SPEED_FRACTION, Motion
from services.sim.render_time import RenderWait
from services.sim.scene_file import (
    DEFAULT_SCENE,
    SceneError,
    SceneSpec,
    load_scene,
    parse_scene,
    randomized,
    with_positions,
)
from services.sim.world import ARMS, Capture, PictureInFlight, SimWorld
from shared.bus import Bus
from shared.messages import (
    Cloud,
    MotionReply,
    MotionsReply,
    PauseReply,
    SceneReply,
    SimEvent,
    SnapshotReply,
    StepReply,
    StopReply,
    as_received,
    reply_from,
)

log = logging.getLogger("hfpbd.sim")

STATE_RATE = 25.0  # Hz
TRUTH_RATE = 10.0  # Hz
REQUEST_TIMEOUT = 10.0  # s a handler waits for the loop to apply a command
RTF_WINDOW = 3.0  # s of wall time the published real-time factor is averaged over


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", default=DEFAULT_SCENE, help="scene name or JSON file (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=None, help="place the scene's objects at random with this seed")
    parser.add_argument("--width", type=int, default=640, help="head camera width in pixels (default: %(default)s)")
    parser.add_argument("--height", type=int, default=480, help="head camera height in pixels (default: %(default)s)")
    parser.add_argument(
        "--cloud-rate", type=float, default=5.0, help="point clouds per wall second (default: %(default)s)"
    )
    parser.add_argument(
        "--speed",
        type=float,
        default=1.0,
        help="simulated seconds per wall second; 0 = as fast as possible (default: %(default)s)",
    )
    parser.add_argument("--paused", action="store_true", help="start paused (advance with sim/control/step)")


def resolve_scene(request: dict[str, Any]) -> SceneSpec:
    """The scene a load request names, with its seed and pose overrides applied."""
    if "scene" in request and isinstance(request["scene"], dict):
        scene = parse_scene(request["scene"], source="inline scene")
    else:
        name = request.get("name") or request.get("path")
        if not isinstance(name, str) or not name:
            raise SceneError("a scene request needs 'name' (e.g. 'default') or 'path' to a scene file")
        scene = load_scene(name)
    if request.get("seed") is not None:
        seed = request["seed"]
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise SceneError(f"seed must be an integer, got {seed!r}")
        scene = randomized(scene, seed)
    if request.get("poses"):
        if not isinstance(request["poses"], dict):
            raise SceneError("poses must map object ids to [x, y] or [x, y, z]")
        scene = with_positions(scene, request["poses"])
    return scene


class SimRunner:
    """Owns the world; other threads hand it work through :meth:`call`."""

    def __init__(self, world: SimWorld, bus: Bus, cloud_rate: float, speed: float, paused: bool) -> None:
        self.world = world
        self.bus = bus
        self.cloud_rate = cloud_rate
        self.speed = speed
        self.paused = paused
        self._inbox: queue.Queue[tuple[Callable[[], Any], Future]] = queue.Queue()
        self._frames: queue.Queue[Capture | None] = queue.Queue(maxsize=1)
        self._render_wait = RenderWait()
        self._state_pub = bus.publisher(bus.keys.sim_state)
        self._truth_pub = bus.publisher(bus.keys.truth)
        self._cloud_pub = bus.publisher(bus.keys.cloud, large=True)
        self._rtf_window: deque[tuple[float, float]] = deque()
        self.rtf = 0.0
        self.clouds_published = 0
        self._cloud_thread = threading.Thread(target=self._publish_clouds, name="sim-clouds", daemon=True)

    # -- called from request handlers --------------------------------------------
    def call(self, work: Callable[[], Any]) -> Any:
        """Run ``work()`` on the simulation thread and return its result (or raise its error)."""
        future: Future = Future()
        self._inbox.put((work, future))
        return future.result(timeout=REQUEST_TIMEOUT)

    # -- the loop ------------------------------------------------------------------
    def run(self, stop: threading.Event) -> None:
        self._cloud_thread.start()
        world = self.world
        wall0, sim0 = time.monotonic(), world.sim_time
        next_state = next_truth = next_cloud = time.monotonic()
        picture: PictureInFlight | None = None  # a frame the renderer is drawing, taken at ``taken_at``
        taken_at = 0.0
        try:
            while not stop.is_set():
                self._apply_commands()
                now = time.monotonic()
                if self.paused:
                    wall0, sim0 = now, world.sim_time
                    time.sleep(0.004)
                elif self.speed > 0 and world.sim_time - sim0 > (now - wall0) * self.speed:
                    time.sleep(min(0.004, world.sim_time - sim0 - (now - wall0) * self.speed))
                else:
                    self._step()
                    if self.speed > 0 and (now - wall0) * self.speed - (world.sim_time - sim0) > 0.5:
                        wall0, sim0 = now, world.sim_time  # too far behind: do not sprint to catch up
                now = time.monotonic()
                self._rtf_window.append((now, world.sim_time))
                while now - self._rtf_window[0][0] > RTF_WINDOW:
                    self._rtf_window.popleft()
                if now >= next_state:
                    next_state = max(next_state + 1.0 / STATE_RATE, now)
                    self.publish_state()
                if now >= next_truth:
                    next_truth = max(next_truth + 1.0 / TRUTH_RATE, now)
                    self.publish_truth()
                if picture is not None and self._render_wait.ready(taken_at, now):
                    self._read_frame(picture)
                    picture = None
                if self.cloud_rate > 0 and now >= next_cloud and picture is None:
                    next_cloud = max(next_cloud + 1.0 / self.cloud_rate, now)
                    picture, taken_at = world.take_picture(), now
        finally:
            self._offer_frame(None)
            self._cloud_thread.join(timeout=5.0)

    def _read_frame(self, picture: PictureInFlight) -> None:
        started = time.monotonic()
        frame = self.world.read_picture(picture)
        self._render_wait.learn(time.monotonic() - started)
        if frame is not None:
            self._offer_frame(frame)

    def _apply_commands(self) -> None:
        while True:
            try:
                work, future = self._inbox.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                try:
                    future.set_result(work())
                except Exception as exc:  # the handler turns it into an error reply
                    future.set_exception(exc)

    def _step(self) -> None:
        for motion, status, message in self.world.step():
            self.publish_event(motion.motion_id, status, message)
        if self.world.came_to_rest:
            self.publish_state()

    def step_paused(self, steps: int) -> float:
        for _ in range(steps):
            self._step()
        return self.world.sim_time

    # -- publishing ------------------------------------------------------------------
    def publish_event(self, motion_id: str, status: str, message: str) -> None:
        event = SimEvent(
            motion_id=motion_id, status=status, message=message, sim_time=self.world.sim_time, stamp=time.time()
        )
        self.bus.publish(self.bus.keys.sim_events, event)

    def replaced(self, old: Motion | None, new_id: str) -> None:
        if old is not None:
            self.publish_event(old.motion_id, "stopped", f"replaced by {new_id}")

    def _measure_rtf(self) -> float:
        if len(self._rtf_window) < 2:
            return 0.0
        (w0, s0), (w1, s1) = self._rtf_window[0], self._rtf_window[-1]
        return (s1 - s0) / (w1 - w0) if w1 > w0 else 0.0

    def publish_state(self) -> None:
        self.rtf = self._measure_rtf()
        state = self.world.state()
        state.update(stamp=time.time(), rtf=self.rtf, paused=self.paused)
        self._state_pub.put(as_received("sim_state", state))

    def publish_truth(self) -> None:
        truth = {"stamp": time.time(), "sim_time": self.world.sim_time, "scene": self.world.scene_name}
        self._truth_pub.put(as_received("truth", {**truth, "objects": self.world.truth()}))

    def _offer_frame(self, frame: Capture | None) -> None:
        """Hand a frame to the cloud thread, replacing one it has not started on (newest wins)."""
        try:
            self._frames.get_nowait()
        except queue.Empty:
            pass
        self._frames.put(frame)

    def _publish_clouds(self) -> None:
        while (frame := self._frames.get()) is not None:
            try:
                self._cloud_pub.put(Cloud(**cloud_message(frame, time.time())))
                self.clouds_published += 1
            except Exception:
                log.exception("publishing a point cloud failed")


def serve_controls(bus: Bus, runner: SimRunner) -> None:
    """Declare the ``sim/control/*`` queryables."""
    world = runner.world
    joints = world.joints
    keys = bus.keys

    def start_arm(side: str, names: list[str], goal: Any, contact: bool) -> str:
        """Start one arm's motion (on the simulation thread)."""
        motion_id = world.new_motion_id()
        if isinstance(goal, tuple):
            times, points = goal
            runner.replaced(world.follow_waypoints(side, names, times, points, motion_id, contact), motion_id)
        else:
            runner.replaced(world.move_joints(side, names, goal, motion_id), motion_id)
        return motion_id

    def arm(request: dict) -> MotionReply:
        side, names, goal = control.arm_request(request, joints)
        contact = control.contact_flag(request)
        if contact and not isinstance(goal, tuple):
            raise ValueError("contact applies to timed waypoints ('points' and 'times'), not to 'positions'")
        return MotionReply(ok=True, motion_id=runner.call(lambda: start_arm(side, names, goal, contact)))

    def arms(request: dict) -> MotionsReply:
        motions = control.arms_request(request, joints)
        # one call on the simulation thread: every arm starts before the next physics step
        ids = runner.call(
            lambda: {side: start_arm(side, names, goal, contact) for side, names, goal, contact in motions}
        )
        return MotionsReply(ok=True, motion_ids=ids)

    def gripper(request: dict) -> MotionReply:
        side, width, force = control.gripper_request(request)

        def start() -> str:
            motion_id = world.new_motion_id()
            runner.replaced(world.move_gripper(side, width, force, motion_id), motion_id)
            return motion_id

        return MotionReply(ok=True, motion_id=runner.call(start))

    def head(request: dict) -> MotionReply:
        goal = control.head_request(request, joints)

        def start() -> str:
            pan, tilt = world.head_angles_for(goal) if isinstance(goal, np.ndarray) else goal
            motion_id = world.new_motion_id()
            runner.replaced(
                world.move_joints("head", ["head_pan_joint", "head_tilt_joint"], np.array([pan, tilt]), motion_id),
                motion_id,
            )
            return motion_id

        return MotionReply(ok=True, motion_id=runner.call(start))

    def torso(request: dict) -> MotionReply:
        height = control.torso_request(request, joints)

        def start() -> str:
            motion_id = world.new_motion_id()
            runner.replaced(
                world.move_joints("torso", ["torso_lift_joint"], np.array([height]), motion_id, TORSO_SPEED_FRACTION),
                motion_id,
            )
            return motion_id

        return MotionReply(ok=True, motion_id=runner.call(start))

    def stop(request: dict) -> StopReply:
        parts = control.stop_parts(request)

        def halt() -> list[str]:
            stopped = world.stop(parts)
            for motion in stopped:
                runner.publish_event(motion.motion_id, "stopped", "stopped on request")
            return [m.motion_id for m in stopped]

        return StopReply(ok=True, stopped=runner.call(halt))

    def scene(request: dict) -> SceneReply:
        spec = resolve_scene(request)

        def load() -> list[dict]:
            for motion in list(world.motions.values()):
                runner.publish_event(motion.motion_id, "stopped", f"scene {spec.name} loaded")
            world.load(spec)
            world.settle(0.3)
            runner.publish_truth()
            return world.truth()

        return reply_from(SceneReply, {"ok": True, "scene": spec.name, "objects": runner.call(load)})

    def pause(request: dict) -> PauseReply:
        paused = request.get("paused", True)
        if not isinstance(paused, bool):
            raise ValueError("paused must be true or false")

        def apply() -> float:
            runner.paused = paused
            return world.sim_time

        return PauseReply(ok=True, paused=paused, sim_time=runner.call(apply))

    def step(request: dict) -> StepReply:
        steps = int(control.number(request, "steps", 1, 25000, 1))

        def apply() -> float:
            if not runner.paused:
                raise ValueError('step needs the simulation paused (sim/control/pause {"paused": true})')
            sim_time = runner.step_paused(steps)
            runner.publish_state()
            runner.publish_truth()
            return sim_time

        return StepReply(ok=True, sim_time=runner.call(apply))

    def snapshot(request: dict) -> SnapshotReply:
        image = runner.call(world.overview_rgb)
        return SnapshotReply(ok=True, png=png_bytes(image))

    handlers = {
        "arm": arm,
        "arms": arms,
        "gripper": gripper,
        "head": head,
        "torso": torso,
        "stop": stop,
        "scene": scene,
        "pause": pause,
        "step": step,
        "snapshot": snapshot,
    }
    for name, handler in handlers.items():
        bus.serve(keys.sim_control(name), handler)


def png_bytes(rgb: np.ndarray) -> bytes:
    ok, encoded = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise RuntimeError("PNG encoding failed")
    return encoded.tobytes()


def run(bus: Bus, args: argparse.Namespace, stop: threading.Event) -> None:
    """Service body: build the world, load the scene, serve, loop until stopped."""
    scene = resolve_scene({"name": args.scene, "seed": args.seed})
    world = SimWorld(width=args.width, height=args.height)
    world.load(scene)
    world.settle(0.3)
    log.info("scene %s loaded: %s", scene.name, ", ".join(scene.ids))
    world.capture()  # the first frame compiles shaders (seconds on a CPU); do it before going live
    runner = SimRunner(world, bus, args.cloud_rate, args.speed, args.paused)
    serve_controls(bus, runner)
    bus.declare_alive("sim")
    log.info(
        "simulating at %s real time, clouds %dx%d at %.1f Hz, arms %s",
        "max" if args.speed <= 0 else f"{args.speed:g}x",
        args.width,
        args.height,
        args.cloud_rate,
        ARMS,
    )
    runner.run(stop)
