"""Record runs for the rerun viewer: the synodic scene in 3-D and the step metrics over time.

Registered as recorder ``"rerun"``. The recorder is a lifecycle observer: register an instance
with the run's plugin manager and it logs every event of the run to its own
:class:`rerun.RecordingStream` (never the global one), written to an ``.rrd`` file, served to
viewers over gRPC on 127.0.0.1, or streamed to a native viewer it starts.

What is logged (entity paths; positions in km, synodic frame, Earth–Moon barycentre at 0):

=============================  ==========================================================
``world/earth``, ``world/moon``  the primaries as spheres of radius 6378.137 / 1737.4 km (static)
``world/libration``             L1..L5 of the run's mass ratio (static, labelled)
``world/truth/trajectory``      the dense truth trajectory (static)
``world/truth/position``        the truth at each step
``world/particles``             the belief's particles at each event, class id = component
``world/components``            n-sigma position ellipsoids of the ``max_ellipsoids`` heaviest mixture
                                components (weights as hidden labels, shown on hover)
``world/estimate``              the mixture mean
``world/estimate_frame``        transform of the run view's frame: radial / along-track / cross-track
                                about the mean, one unit per axis = the cloud's extent along it
                                (:mod:`.estimate_frame`)
``world/estimate_frame/axes``   the frame's three axes, one unit long, and ``.../axis_labels`` their
                                names and units in km ("radial ±4,755 km"), in the view's corner
``world/estimate_frame/...``    ``line_of_sight``: the line of sight near the estimate, frame units;
                                ``truth_path``: the truth trajectory near the estimate; ``legend``:
                                each component's colour and weight (:mod:`.run_view_log`)
``world/observer``              the observer's position at each step
``world/line_of_sight``         the measured line of sight at update steps (cleared otherwise)
``world/observers/<key>/...``   every observer, its lines of sight and exclusion cones (observers_view)
``metrics/<name>``              every finite metric of ``step.metrics`` (steps that carry metrics)
``diagnostics/<name>``          the filter's numeric diagnostics on the same steps
``components/weights``          the mixture weights, one series per component
``components/ranked/<k>``       the k-th largest weight (0 beyond the components there are)
``series/<panel>/<name>``       log10 of errors and sigmas, NEES and its chi-square band (:mod:`.run_series`)
``run/info``, ``run/summary``   text: run id, components, seed; the run's summary
``maneuvers/...``, ...          truth burns, the detector's statistic, detections, estimated burns
                                (:mod:`.maneuver_marks`)
=============================  ==========================================================

Timelines: ``step`` (step index), ``utc`` (simulation time) and ``event`` (one tick per hook
call, so the prior and the posterior of one step can be told apart when scrubbing).

(Above 300 lines with this table: one recorder class whose hooks share one recording stream and
event counter; the viewer process is in :mod:`.viewer_process`, the blueprint in
:mod:`.blueprint`, the scene geometry in :mod:`.scene`, the run view's frame and series in
:mod:`.run_view_log`.)
"""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import uuid
import warnings
from datetime import timedelta
from pathlib import Path
from typing import Any

import numpy as np


from cistrack.interfaces.component import Component, check_int, check_positive
from cistrack.errors import ParameterError
from cistrack.api import hookimpl
from cistrack.lazy import LazyModule
from cistrack.units import LU_KM, parse_utc

from .blueprint import APPLICATION_ID
from .blueprint_inputs import BlueprintInputs
from .decimation import heaviest_components, subsample_indices
from .estimate_frame import line_through_frame
from .maneuver_marks import ManeuverMarks
from .observers_view import log_observers
from .run_extents import set_step_times, system_points_km, utc_at, utc_range_s
from .run_series import log10_series
from .run_view_log import (log_estimate_frame, log_legend, log_run_view_styles, log_series, log_truth_path,
                           truth_path_in_frame)
from .viewer_process import (LOOPBACK, ViewerUnavailableError, check_viewer, find_viewer_executable,
                             start_viewer)
from .view_frame import VIEW_FRAMES, ViewFrame
from .scene import (
    EARTH_RADIUS_KM, LIBRATION_NAMES, MOON_RADIUS_KM, libration_points, most_likely_component,
    position_ellipsoids, primary_positions, system_mu,
)

# rerun loads when a recording starts, not when the registry lists this plugin.
rr = LazyModule("rerun")
rrb = LazyModule("rerun.blueprint")

__all__ = ["RerunRecorder", "ViewerUnavailableError", "subsample_indices", "LOOPBACK",
           "find_viewer_executable"]

UNASSIGNED_CLASS = 999
"""Class id of particles without a component label (a clusterer's noise label, < 0)."""

# Colour per component (class id); beyond the palette the viewer picks its own colours.
_PALETTE = np.array([
    (31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
    (140, 86, 75), (227, 119, 194), (188, 189, 34), (23, 190, 207), (127, 127, 127),
    (174, 199, 232), (255, 187, 120), (152, 223, 138), (255, 152, 150), (197, 176, 213),
    (196, 156, 148),
], dtype=np.uint8)


def _port_in_use(port: int) -> bool:
    """Whether 127.0.0.1:``port`` cannot be bound now (another server holds it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((LOOPBACK, port))
        except OSError:
            return True
    return False


MIN_FREE_BYTES = 32_000_000
"""Free disk space a recording to a file asks for before the run: rerun's file sink, once the
disk is full, leaves the process waiting in its own code for ever (no signal ends it), so a disk
short of room is refused up front. A disk that fills during the run: :data:`LOW_FREE_BYTES`."""

LOW_FREE_BYTES = 16_000_000
"""Free disk space below which a recording to a file stops between two steps (flushed and
closed while its last batch still fits; the run goes on and says so), before rerun's file
writer meets a full disk."""

RECORDING_MAGIC = b"RRF"
"""The first bytes of a rerun recording file (``RRF2`` for rerun 0.2x's)."""


def is_recording_or_empty(path: str | os.PathLike) -> bool:
    """Whether the file at ``path`` is a rerun recording (it starts with :data:`RECORDING_MAGIC`) or
    empty: the only files a recorder with ``overwrite`` replaces. False when it cannot be read."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(len(RECORDING_MAGIC))
    except OSError:
        return False
    return head in (b"", RECORDING_MAGIC)


class RerunRecorder(Component):
    """Record a run for the rerun viewer (3-D synodic scene, clouds, ellipsoids, metrics).

    Parameters
    ----------
    path : str or None
        Write the recording to this ``.rrd`` file. For studies: a path containing ``{run_id}``
        or naming an existing directory writes one file per run (``<dir>/<run_id>.rrd``).
    serve : bool
        Serve the recording over gRPC on 127.0.0.1:``serve_port`` for viewers to connect to
        (``rerun rerun+http://127.0.0.1:<port>/proxy``). Never listens on other interfaces.
    spawn : bool
        Start the native viewer (bound to 127.0.0.1:``viewer_port``) and stream to it; raises
        :class:`ViewerUnavailableError` at construction when no viewer or no display exists.
    max_points : int
        At most this many particles are logged per event: a seeded, deterministic subsample in
        which every mixture component keeps particles (at least 2 % of those logged, or all of
        its own), the rest drawn in proportion to the components' sizes (:mod:`.decimation`).
    max_ellipsoids : int
        Position ellipsoids of at most this many mixture components are logged per event, the
        heaviest ones (their particles are all coloured and counted in the legend).
    serve_port : int
        Port of the gRPC server for ``serve`` (rerun's default is 9876).
    viewer_port : int
        Port the spawned viewer listens on for ``spawn``.
    ellipsoid_sigma : float
        Mahalanobis radius of the component position ellipsoids (3 = 3-sigma).
    subsample_seed : int
        Seed of the particle subsample.
    frame : str
        Frame of the 3-D scene: "synodic" (the run's rotating frame) or "inertial" (the
        sensor's Earth-centred inertial frame, e.g. GCRS for the real-geometry sensor; the Moon
        then moves and the libration points are not drawn). See :mod:`.view_frame`.
    overwrite : bool
        Replace a recording file that already exists (``cistrack run --overwrite``). Without it
        an existing file is refused, at construction for a plain ``path`` and when the run
        starts for a per-run file, so that a recording is never clobbered by accident.
    """

    kind = "recorder"

    def __init__(self, path: str | None = None, serve: bool = False, spawn: bool = False,
                 max_points: int = 2_000, serve_port: int = 9876, viewer_port: int = 9877,
                 ellipsoid_sigma: float = 3.0, subsample_seed: int = 0, frame: str = "synodic",
                 overwrite: bool = False, max_ellipsoids: int = 4) -> None:
        if path is not None and not isinstance(path, (str, os.PathLike)):
            self._fail("path", path, "must be a file path (str) or None")
        self.path = None if path is None else os.fspath(path)
        special = _not_a_file_to_write(self.path)
        if special:
            self._fail("path", self.path, f"{special}, which a recording is never written to; give the path of a file "
                                          "or a directory")
        for name, value in (("serve", serve), ("spawn", spawn), ("overwrite", overwrite)):
            if not isinstance(value, (bool, np.bool_)):
                self._fail(name, value, "must be true or false")
        self.serve = bool(serve)
        self.spawn = bool(spawn)
        self.overwrite = bool(overwrite)
        self.max_points = check_int(self, "max_points", max_points, minimum=1)
        self.max_ellipsoids = check_int(self, "max_ellipsoids", max_ellipsoids, minimum=0)
        self.serve_port = check_int(self, "serve_port", serve_port, minimum=0, maximum=65535)
        self.viewer_port = check_int(self, "viewer_port", viewer_port, minimum=1, maximum=65535)
        self.ellipsoid_sigma = check_positive(self, "ellipsoid_sigma", ellipsoid_sigma)
        self.subsample_seed = check_int(self, "subsample_seed", subsample_seed, minimum=0)
        if frame not in VIEW_FRAMES:
            self._fail("frame", frame, f"must be one of {', '.join(map(repr, VIEW_FRAMES))}")
        self.frame = frame
        self._view: ViewFrame | None = None
        self._marks: ManeuverMarks | None = None
        if self.path is None and not self.serve and not self.spawn:
            raise ParameterError(f"{self._label()}: nothing to record to; give a path, serve=True "
                                 "or spawn=True")
        if self.spawn:
            check_viewer()
        # Checked here, before a run computes anything: a taken port or an unwritable file would
        # otherwise only fail when the run starts recording.
        if self.serve and self.serve_port and _port_in_use(self.serve_port):
            self._fail("serve_port", self.serve_port,
                       f"127.0.0.1:{self.serve_port} is already in use (another viewer or run?); stop "
                       "that process or give another serve_port (cistrack run --rerun-port N)")
        if self.path is not None:
            self._check_path()
        self._rec: rr.RecordingStream | None = None
        self._viewer: subprocess.Popen | None = None
        self._event = 0
        self._epoch = None
        self._files: list[str] = []
        self._mu = 0.0
        self._n_ranks = 0
        self._truth: tuple[np.ndarray, np.ndarray] | None = None  # trajectory (N, 3) km, times (N,)

    # -- pickling: the stream and the viewer process stay in the process that made them ----------
    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_rec"] = None
        state["_viewer"] = None
        state["_marks"] = None  # holds the run's maneuver watch
        return state

    # -- what a caller may ask after run_started --------------------------------------------------
    @property
    def server_uri(self) -> str | None:
        """URI a viewer connects to when ``serve`` is on (``rerun <uri>``), else None."""
        return f"rerun+http://{LOOPBACK}:{self.serve_port}/proxy" if self.serve else None

    @property
    def files(self) -> list[str]:
        """The ``.rrd`` files written so far, one per run."""
        return list(self._files)

    def close(self) -> None:
        """Flush and drop the recording stream (this stops a ``serve`` server)."""
        rec, self._rec = self._rec, None
        if rec is not None:
            rec.flush()
            rr.bindings.finalize_deferred_sinks(recording=rec.to_native())
            rec.disconnect()

    # -- lifecycle hooks --------------------------------------------------------------------------
    @staticmethod
    def serve_file(path: str, web_port: int = 9090, option: str = "--port"):
        """Serve a recording and the web viewer on 127.0.0.1 (see :mod:`.web_viewer`); the
        returned object's ``url`` loads it, ``close()`` stops serving. ``option`` names what chose
        ``web_port`` in errors (out of range, in use)."""
        from .web_viewer import serve_recording

        return serve_recording(path, web_port=web_port, option=option)

    @hookimpl
    def cistrack_run_started(self, run) -> None:
        """Open the run's recording and log the static scene and the truth trajectory."""
        self.close()
        self._view = ViewFrame(self.frame, run)
        self._epoch = parse_utc(run.epoch)
        self._marks = ManeuverMarks(run, self._view, self._epoch)
        self._rec = self._open(run)
        self._event = 0
        self._n_ranks = 0
        self._truth = None
        self._mu = system_mu(run.dynamics)
        self._log_scene(self._rec, run)
        self._marks.log_start(self._rec, run)

    @hookimpl
    def cistrack_step_predicted(self, run, step) -> None:
        """Log a prior (or the initial / a predict-only step): particles, ellipsoids, truth,
        observer, and the step's metrics when it has them."""
        self._log_step(run, step)

    @hookimpl
    def cistrack_step_updated(self, run, step) -> None:
        """Log the posterior of a step, its line of sight and its metrics."""
        self._log_step(run, step)

    @hookimpl
    def cistrack_run_finished(self, run, summary) -> None:
        """Log the summary; flush and close the file (a server stays up until :meth:`close`)."""
        rec = self._rec
        if rec is None:
            return
        data = summary.to_dict() if hasattr(summary, "to_dict") else dict(summary or {})
        lines = [f"- **{k}**: {v}" for k, v in data.items()]
        rec.log("run/summary", rr.TextDocument("\n".join(lines) or "(no summary)",
                                               media_type=rr.MediaType.MARKDOWN), static=True)
        if self._marks is not None:
            self._marks.log_finish(rec, summary)
        rec.flush()
        rr.bindings.finalize_deferred_sinks(recording=rec.to_native())
        if not (self.serve or self.spawn):
            self.close()

    # -- internals --------------------------------------------------------------------------------
    def _check_path(self) -> None:
        """Refuse, before a run computes anything, a ``path`` that is not an .rrd file or a directory,
        whose folder cannot be written or has no room, or an existing file :meth:`_refuse_existing` refuses."""
        target = Path(self.path)
        if not target.is_dir() and not self.path.lower().endswith(".rrd"):
            self._fail("path", self.path, "must end in .rrd (the rerun viewer and cistrack view read recordings "
                       "by that name), or name a directory for one recording per run")
        folder = target if target.is_dir() else target.parent  # a directory: one file per run
        if not folder.is_dir() or not os.access(folder, os.W_OK):
            self._fail("path", self.path, f"cannot be written: directory {folder} does not exist or is "
                       "not writable")
        free = _free_bytes(folder)
        if free < MIN_FREE_BYTES:
            self._fail("path", self.path, f"only {free / 1e6:.3g} MB free on the disk of {folder}; a recording "
                       f"needs room (Example 1: about 4 MB) and rerun's file writer cannot report a full disk "
                       f"(it waits for ever), so at least {MIN_FREE_BYTES / 1e6:g} MB free are asked for")
        if "{run_id}" not in self.path and not target.is_dir():
            self._refuse_existing(self.path)

    def _refuse_existing(self, target: str) -> None:
        """Refuse to replace an existing file ``target`` unless ``overwrite`` is on, and with it a
        file that is not a rerun recording (a scenario or observation file given as the path by
        mistake: ``overwrite`` replaces recordings, never other files)."""
        if not os.path.lexists(target):
            return
        if not self.overwrite:
            self._fail("path", target, "already exists; give another file, or overwrite=true "
                       "(cistrack run --overwrite) to replace it")
        if not is_recording_or_empty(target):
            self._fail("path", target, "already exists and is not a rerun recording (it does not start with rerun's "
                       "RRF header): overwrite=true replaces recordings only; give another file name ending in .rrd")

    def _file_for(self, run_id: str) -> str | None:
        if self.path is None:
            return None
        safe = "".join(c if (c.isalnum() or c in "-_.") else "_" for c in run_id)
        if "{run_id}" in self.path or os.path.isdir(self.path):
            target = (self.path.replace("{run_id}", safe) if "{run_id}" in self.path
                      else os.path.join(self.path, f"{safe}.rrd"))
            if target not in self._files:
                self._refuse_existing(target)
            return target
        if self._files and self._files[-1] == self.path:
            raise ParameterError(
                f"{self._label()}: parameter 'path' = {self.path!r} names one file but a second run "
                f"({run_id!r}) started; use a directory or a path containing '{{run_id}}'")
        return self.path

    def _open(self, run) -> rr.RecordingStream:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4(), send_properties=True,
                                 batcher_config=None if self.serve or self.spawn else _file_batching())
        rec.set_log_time_enabled(False)  # wall-clock time says nothing about the run
        sinks: list[Any] = []
        target = self._file_for(str(run.run_id))
        if target is not None:
            Path(target).parent.mkdir(parents=True, exist_ok=True)
            sinks.append(rr.FileSink(target))
            self._files.append(target)
        if self.serve:
            sinks.append(rr.GrpcServerSink(bind_ip=LOOPBACK, port=self.serve_port))
        if self.spawn:
            sinks.append(rr.GrpcSink(self._start_viewer()))
        marks = self._marks
        inputs = BlueprintInputs.of(system_points_km(run, self._view), utc_range_s(run, self._epoch),
                                    watching=marks is not None and marks.watching,
                                    burns=marks is not None and bool(marks.burns))
        rec.set_sinks(*sinks, default_blueprint=inputs.blueprint(live=self.serve or self.spawn))
        rec.send_recording_name(str(run.run_id))
        inputs.send(rec)  # so that cistrack view can build the blueprint again for a slower viewer
        if not (self.serve or self.spawn):  # a live viewer may still be starting: no wait for it here
            rec.flush()  # the properties as the file's first chunks, where cistrack view looks for them
        return rec

    def _start_viewer(self) -> str:
        check_viewer()
        if self._viewer is None or self._viewer.poll() is not None:
            self._viewer = start_viewer(self.viewer_port)
        return f"rerun+http://{LOOPBACK}:{self.viewer_port}/proxy"

    def _set_time(self, rec: rr.RecordingStream, index: int, t: float) -> None:
        set_step_times(rec, self._event, index, utc_at(self._epoch, t))
        self._event += 1

    def _log_scene(self, rec: rr.RecordingStream, run) -> None:
        mu = system_mu(run.dynamics)
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        classes = [rr.AnnotationInfo(id=i, label=f"component {i}", color=tuple(int(c) for c in col))
                   for i, col in enumerate(_PALETTE)]
        classes.append(rr.AnnotationInfo(id=UNASSIGNED_CLASS, label="unassigned", color=(90, 90, 90)))
        rec.log("world", rr.AnnotationContext(classes), static=True)
        view = self._view
        prim = primary_positions(mu) * LU_KM if view.is_synodic else np.zeros((2, 3))
        rec.log("world/earth", rr.Ellipsoids3D(centers=prim[:1], radii=[EARTH_RADIUS_KM],
                                               colors=[(40, 90, 200)], labels=["Earth"],
                                               fill_mode=rr.components.FillMode.Solid), static=True)
        if view.is_synodic:  # inertial: the Moon moves and is logged at every step
            rec.log("world/moon", rr.Ellipsoids3D(centers=prim[1:], radii=[MOON_RADIUS_KM],
                                                  colors=[(170, 170, 170)], labels=["Moon"],
                                                  fill_mode=rr.components.FillMode.Solid), static=True)
            rec.log("world/libration", rr.Points3D(libration_points(mu) * LU_KM, labels=list(LIBRATION_NAMES),
                                                   show_labels=True, colors=[(240, 200, 60)],
                                                   radii=rr.Radius.ui_points(4.0)), static=True)
        if run.has_truth:
            truth = view.states(run.truth_states, run.truth_times)
            self._truth = (truth[:, :3] * LU_KM, np.asarray(run.truth_times, dtype=float))
            rec.log("world/truth/trajectory",
                    rr.LineStrips3D([truth[:, :3] * LU_KM],
                                    colors=[(230, 230, 230)], radii=rr.Radius.ui_points(1.0)),
                    static=True)
        info = [f"- **run**: {run.run_id}", f"- **seed**: {run.seed}",
                f"- **epoch**: {self._epoch.isoformat()}", f"- **mass ratio**: {mu}"]
        for kind in ("dynamics", "sensor", "schedule", "iod", "filter"):
            comp = getattr(run, kind, None)
            if comp is not None:
                info.append(f"- **{kind}**: {comp!r}")
        info.append(f"- **measurements**: {len(run.measurements)}")
        rec.log("run/info", rr.TextDocument("\n".join(info), media_type=rr.MediaType.MARKDOWN),
                static=True)
        log_run_view_styles(rec)

    def _log_cloud(self, rec: rr.RecordingStream, states: np.ndarray, labels: np.ndarray | None,
                   mixture, t: float = 0.0) -> np.ndarray:
        """Log the particles (at most ``max_points``, every component kept) in km; returns their
        positions (N, 3) km."""
        states = np.asarray(states, dtype=float)
        cls = _particle_classes(states, labels, mixture)
        keep = subsample_indices(states.shape[0], self.max_points, self.subsample_seed, labels=cls)
        if keep is not None:
            states, cls = states[keep], cls[keep]
        pos = states[:, :3] if self._view is None else self._view.states(states, t)[:, :3]
        km = (pos * LU_KM).astype(np.float32)
        rec.log("world/particles", rr.Points3D(km, class_ids=cls, radii=rr.Radius.ui_points(2.0)))
        return km.astype(float)

    def _log_step(self, run, step) -> None:
        rec = self._rec
        if rec is None or self._disk_short(run, step):  # no run_started, or stopped: nothing to log to
            return
        self._set_time(rec, step.index, step.t)
        belief = step.belief
        mix = belief.mixture
        t = float(step.t)
        cloud_km = self._log_cloud(rec, belief.samples.states, belief.samples.labels, mix, t)
        self._log_moon(rec, run, t)
        self._log_components(rec, mix, t)
        frame = self._log_estimate(rec, mix, cloud_km, t)
        if step.truth is not None:
            truth_km = self._view.states(step.truth, t)[:, :3] * LU_KM
            rec.log("world/truth/position", rr.Points3D(truth_km, colors=[(255, 255, 255)],
                                                        radii=rr.Radius.ui_points(6.0)))
            if self._truth is not None:
                log_truth_path(rec, truth_path_in_frame(*self._truth, t, truth_km[0], frame))
        obs = np.asarray(run.sensor.observer_position(float(step.t)), dtype=float).reshape(3)
        rec.log("world/observer", rr.Points3D(self._view.positions(obs, t) * LU_KM, colors=[(0, 230, 120)],
                                              radii=rr.Radius.ui_points(5.0)))
        self._log_line_of_sight(rec, run.sensor, step, obs, frame)
        log_observers(rec, run, step, self._view, np.asarray(mix.mean[:3], dtype=float))  # every observer, its cones
        if step.metrics:  # one metrics row per results-table row (priors of updates have none)
            _log_numbers(rec, "metrics", step.metrics)
            _log_numbers(rec, "diagnostics", step.diagnostics)
            rec.log("components/weights", rr.Scalars(np.asarray(mix.weights, dtype=float)))
            self._n_ranks = log_series(rec, step.metrics, mix.weights, self._n_ranks)
            if self._marks is not None:
                self._marks.log_step(rec, step, log10_series(step.metrics).get("series/nees/nees"), self._event - 1)

    def _disk_short(self, run, step) -> bool:
        """Whether the recording's file has just been stopped (flushed and closed) because its disk
        is short of room (:data:`LOW_FREE_BYTES`), with a RuntimeWarning saying why."""
        target = self._files[-1] if self._files else None
        if target is None or _free_bytes(os.path.dirname(os.path.abspath(target))) >= LOW_FREE_BYTES:
            return False
        self.close()
        warnings.warn(f"cistrack: recording {target} stopped at step {step.index}: under {LOW_FREE_BYTES / 1e6:g} MB "
                      "free on its disk; it holds the run up to here and the run goes on without it",
                      RuntimeWarning, stacklevel=2)
        return True

    def _log_moon(self, rec: rr.RecordingStream, run, t: float) -> None:
        """The Moon as a solid sphere (km) in views where it moves (not the synodic one)."""
        if self._view.is_synodic:
            return
        moon = run.dynamics.primary("Moon")
        if moon is not None:
            rec.log("world/moon", rr.Ellipsoids3D(
                centers=self._view.positions(moon.position_at(t), t) * LU_KM, radii=[MOON_RADIUS_KM],
                colors=[(170, 170, 170)], labels=["Moon"], fill_mode=rr.components.FillMode.Solid))

    def _log_components(self, rec: rr.RecordingStream, mix, t: float) -> None:
        """The position ellipsoids (km, ``ellipsoid_sigma``) of the ``max_ellipsoids`` heaviest
        components, each with its weight, and the run view's legend of every component."""
        view = self._view
        shown = heaviest_components(mix.weights, self.max_ellipsoids)
        means = view.states(mix.means[shown], t)
        centers, half, quat = position_ellipsoids(
            means, view.covariances(mix.means[shown], mix.covariances[shown], t), self.ellipsoid_sigma)
        rec.log("world/components", rr.Ellipsoids3D(
            centers=centers, half_sizes=half, quaternions=quat, class_ids=shown.astype(np.uint16),
            labels=[f"w={mix.weights[i]:.3f}" for i in shown], show_labels=False,
            fill_mode=rr.components.FillMode.MajorWireframe))
        log_legend(rec, np.asarray(mix.weights, dtype=float))

    def _log_estimate(self, rec: rr.RecordingStream, mix, cloud_km: np.ndarray, t: float) -> tuple:
        """The mixture mean (km) and its local frame; returns (mean (3,) km, axes, units) of
        :func:`log_estimate_frame`."""
        view = self._view
        mean_state = view.states(mix.mean, t)[0]
        mean = mean_state[:3] * LU_KM
        cov = view.covariances(mix.mean[None], mix.covariance[None], t)[0][:3, :3] * LU_KM**2
        earth = view.positions(primary_positions(self._mu)[0], t)[0] * LU_KM
        axes, units = log_estimate_frame(rec, mean, mean_state[3:], cloud_km, cov, earth)
        rec.log("world/estimate", rr.Points3D(mean[None], colors=[(255, 60, 60)],
                                              radii=rr.Radius.ui_points(5.0)))
        return mean, axes, units

    def _log_line_of_sight(self, rec: rr.RecordingStream, sensor, step, obs: np.ndarray, frame: tuple) -> None:
        """The measured line of sight from the observer ``obs`` (3,) LU, 1.2 times as long as the
        farther of the estimate and the truth, in the world and in the estimate's frame; cleared
        at steps without a measurement."""
        if step.measurement is None:
            rec.log("world/line_of_sight", rr.Clear(recursive=False))
            rec.log("world/estimate_frame/line_of_sight", rr.Clear(recursive=False))
            return
        t = float(step.t)
        meas = step.measurement.angles_only()
        los = np.asarray(sensor.line_of_sight(np.asarray(meas.z, dtype=float)[None, :2],
                                              float(step.t)), dtype=float).reshape(3)
        reach = np.linalg.norm(step.belief.mixture.mean[:3] - obs)
        if step.truth is not None:
            reach = max(reach, float(np.linalg.norm(np.asarray(step.truth)[:3] - obs)))
        end = obs + 1.2 * reach * los
        seg = self._view.positions(np.stack([obs, end]), t) * LU_KM
        rec.log("world/line_of_sight", rr.LineStrips3D([seg], colors=[(0, 230, 120)],
                                                       radii=rr.Radius.ui_points(1.0)))
        mean, axes, units = frame
        rec.log("world/estimate_frame/line_of_sight", rr.LineStrips3D(
            [line_through_frame(seg[0], seg[1], mean, axes, units)], colors=[(0, 230, 120)],
            radii=rr.Radius.ui_points(1.0)))


FILE_FLUSH_BYTES = 4 << 20
"""Bytes of logged rows gathered into chunks at a time for a recording to a file only (rerun's
default is 2 MiB or every 0.2 s, which cuts a run of a few seconds into thousands of small chunks,
each with its own header: a larger file that the viewer loads more slowly)."""


def _free_bytes(folder: str | Path) -> int:
    """Free bytes on the disk of ``folder`` (the operating system's figure)."""
    return shutil.disk_usage(folder).free


def _file_batching() -> rr.ChunkBatcherConfig:
    """Batching for a recording nobody watches live: by size only (:data:`FILE_FLUSH_BYTES`)."""
    return rr.ChunkBatcherConfig(flush_tick=timedelta(hours=1), flush_num_bytes=FILE_FLUSH_BYTES)


def _particle_classes(states: np.ndarray, labels: np.ndarray | None, mixture) -> np.ndarray:
    """Class id (N,) uint16 of each particle: its component label (:data:`UNASSIGNED_CLASS` for a
    clusterer's noise label < 0), else its most likely component, else 0."""
    if labels is not None:
        lab = np.asarray(labels)
        return np.where(lab < 0, UNASSIGNED_CLASS, lab).astype(np.uint16)
    if mixture is not None and mixture.n_components > 1:
        return most_likely_component(states, mixture).astype(np.uint16)
    return np.zeros(states.shape[0], dtype=np.uint16)


def _log_numbers(rec: rr.RecordingStream, prefix: str, values: dict) -> None:
    """Each finite real number of ``values`` as a scalar at ``prefix/<name>``."""
    for name, value in values.items():
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
            continue
        v = float(value)
        if np.isfinite(v):
            rec.log(f"{prefix}/{rr.escape_entity_path_part(str(name))}", rr.Scalars(v))


@hookimpl
def cistrack_register(registry) -> None:
    registry.add("recorder", "rerun", RerunRecorder)


def _not_a_file_to_write(path: str | None) -> str:
    """Why ``path`` (which exists) cannot take a recording: a pipe (opening it to write waits for a
    reader), a device such as /dev/full, a socket; "" for a regular file, a directory, a path that
    does not exist yet, or None."""
    import stat

    if path is None or "{run_id}" in path:
        return ""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return ""
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return ""
    kind = ("a named pipe" if stat.S_ISFIFO(mode) else "a character device" if stat.S_ISCHR(mode)
            else "a block device" if stat.S_ISBLK(mode) else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")
    return f"is {kind}, not a regular file"
