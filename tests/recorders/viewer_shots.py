"""Screenshots of a recording in the web viewer at the start, middle and end of the run, and the
pixel measures the browser test applies to them.

The viewer opens paused near the run's first time; Ctrl+ArrowRight steps its time cursor to the
next time with data, so the middle shot steps through half of the recording's ``utc`` times; the
end shot goes to the end of the timeline through the command palette. Positions are fractions of the 1600 x 1000 page (the default
blueprint's layout: 3-D views on the left 60 %, run view above the system view, five series
panels on the right).

Run as a script to write the README pictures:
    .venv/bin/python tests/recorders/viewer_shots.py RUN.rrd docs/img
which writes docs/img/viewer_start.png, viewer_middle.png and viewer_end.png (in 256 colours);
with ``--timing`` it first measures, in a page of its own, how long the recording takes to load
and to play (:func:`timings`) and prints the numbers as JSON;
    .venv/bin/python tests/recorders/viewer_shots.py RUN.rrd --load-only
measures the load only and writes no picture.
"""
from __future__ import annotations

import io
import math
import socket
import time
from pathlib import Path

import numpy as np

SHOTS = ("start", "middle", "end")

RUN_VIEW = (0.13, 0.59, 0.08, 0.58)
"""x0, x1, y0, y1 of the run view's drawing area (page fractions), right of its legend: the
legend's dots and labels are in the components' colours (the cloud is drawn at the centre)."""

POSITION_PANEL = (0.62, 0.98, 0.07, 0.19)
"""x0, x1, y0, y1 of the first time-series panel's plot (page fractions)."""

CLOUD_COLOURS = np.array([(31, 119, 180), (255, 127, 14)])
"""RGB of the first two mixture components (the recorder's palette): particles and ellipsoids of
these colours are the cloud; no axis, line of sight or label of the run view has them."""


KEY_INTERVAL_S = 1.5
"""Seconds between two time steps of a shot. In the software-rendered headless viewer (rerun 0.41),
a burst of about 40 steps 0.3 s apart leaves the particles undrawn at every time afterwards, while
the ellipsoids and series still draw (Example 1, seed 3: the middle shot showed no particle; 20
steps at a time, or 47 steps 1.5 s apart, drew them at every step). The recording itself holds
every step's particles (test_recording_contents.py reads them back)."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def n_times(rrd: str | Path) -> int:
    """How many distinct ``utc`` times the recording's particles were logged at."""
    from .rrd_reading import read_entities

    rows = read_entities(rrd)["/world/particles"]
    return len({r.times["utc"] for r in rows if "utc" in r.times})


def take(rrd: str | Path, out_dir: str | Path, *, settle_s: float = 30.0) -> dict[str, Path]:
    """Serve ``rrd``, open it in headless Chromium and write ``viewer_<shot>.png`` for each of
    :data:`SHOTS` under ``out_dir``; returns shot name -> PNG path."""
    from cistrack.plugins.recorders.web_viewer import serve_recording

    from .headless_browser import screenshots

    keys = {"start": [], "middle": ["Ctrl+ArrowRight"] * (n_times(rrd) // 2),
            # the palette's "Go to end of timeline": stepping on from the middle can pass the last time
            # and wrap round to the first (an Example 1 end shot showed the IOD's cloud)
            "end": ["command:end of timeline"]}
    out = Path(out_dir)
    with serve_recording(rrd, web_port=free_port()) as served:
        pngs = screenshots(served.page_url, [(out / f"viewer_{s}.png", keys[s]) for s in SHOTS],
                           settle_s=settle_s, key_interval_s=KEY_INTERVAL_S)
    return dict(zip(SHOTS, pngs))


POLL_S = 2.0
"""Seconds between two pictures while playing is timed."""


def _image(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def curve_end(img: np.ndarray) -> int:
    """Rightmost column of the position panel holding a curve pixel (-1 without one): the last
    time loaded, since the panel's x axis spans the whole run from the start."""
    r = region(img, POSITION_PANEL).astype(int)
    cols = np.nonzero(((r.max(axis=2) - r.min(axis=2)) > 60).any(axis=0))[0]
    return int(cols.max()) if cols.size else -1


def cursor_column(img: np.ndarray) -> int | None:
    """Column of the position panel where the time cursor is: the one with the most dark grey
    pixels (the cursor is a line of (93, 92, 92), two pixels wide, in rerun 0.41), if they cover
    more than half of its height (None otherwise)."""
    r = region(img, POSITION_PANEL).astype(int)
    dark = ((r.max(axis=2) < 130) & (r.max(axis=2) - r.min(axis=2) < 12)).sum(axis=0)
    col = int(np.argmax(dark))
    return col if dark[col] > 0.5 * r.shape[0] else None


SETTLE_S = 5.0
"""The viewer has loaded when its picture has not changed for this many seconds (and three
pictures)."""


def same_picture(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two pictures (H, W, 3) show the same: fewer than 20 pixels differ by more than 40
    in a channel (JPEG noise and antialiasing differ by less; a missing curve by far more)."""
    return int((np.abs(a.astype(int) - b.astype(int)).max(axis=2) > 40).sum()) < 20


def _time_loading(page, max_s: float) -> tuple[float, float, int]:
    """Seconds from navigating until the viewer first draws (a picture that is not blank) and until
    it shows the run whole (the first of the pictures that stay the same for :data:`SETTLE_S`
    seconds: every panel drawn); also the series' last column in a full-size picture.
    Quick half-size pictures (:meth:`Page.quick_picture`) are taken one after the other: each
    comes with the viewer's next frame, so the times are within one frame of the truth."""
    t0 = time.monotonic()
    up = whole = float("nan")
    settled: np.ndarray | None = None  # the first picture of the latest run of equal pictures
    n_same = 0
    while time.monotonic() - t0 < max_s:
        img = _image(page.quick_picture())
        t = time.monotonic() - t0
        if math.isnan(up) and img.std() > 5:  # the first picture that is not blank
            up = t
        if settled is None or not same_picture(settled, img):
            settled, whole, n_same = img, t, 1
            continue
        n_same += 1
        if not math.isnan(up) and n_same >= 3 and t - whole >= SETTLE_S:
            break
        time.sleep(0.2)
    return up, whole, curve_end(_image(page.png()))


def _time_playing(page, end_col: int, max_s: float) -> dict:
    """Play from the start (Space) until the cursor reaches ``end_col`` or ``max_s`` passes: the
    seconds, the fraction of the run played, and the whole run's playing time it implies."""
    start = cursor_column(_image(page.png()))
    page.press(" ")
    t0 = time.monotonic()
    col = start
    while time.monotonic() - t0 < max_s:
        time.sleep(POLL_S)
        col = cursor_column(_image(page.png()))
        if col is not None and col >= end_col - 2:
            break
    elapsed = time.monotonic() - t0
    page.press(" ")
    frac = (col - start) / max(end_col - start, 1) if None not in (col, start) else float("nan")
    return {"played_s": round(elapsed, 1), "fraction_played": round(frac, 3),
            "whole_run_s": round(elapsed / frac, 1) if frac > 0 else None}


def timings(rrd: str | Path, *, max_load_s: float = 180.0, max_play_s: float = 150.0, play: bool = True) -> dict:
    """Load and playback times of ``rrd`` in headless Chromium (software rendering, 1600 x 1000),
    opened as ``cistrack view`` says (its opening page, which goes on to the viewer with the
    software renderer's playback speed): ``viewer_up_s`` from opening the URL until the viewer draws, ``load_s`` until it shows the run
    whole (:func:`_time_loading`); ``load_avg``: the 1-minute load average when the page opened.
    Without ``play`` that is all; otherwise ``whole_run_s``: how long
    playing the whole run takes at the speed the viewer opens with (measured over at most
    ``max_play_s`` and extrapolated); ``end_key_moves_to_end``: whether pressing End after Home
    puts the time cursor at the end (not in rerun 0.41's web viewer); ``palette_moves_to_end``:
    whether the command palette's "Go to end of timeline" does (Ctrl+K, "end of timeline", Enter)."""
    from cistrack.plugins.recorders.web_viewer import serve_recording

    from .headless_browser import open_page

    load_avg = float(Path("/proc/loadavg").read_text().split()[0]) if Path("/proc/loadavg").exists() else None
    with serve_recording(rrd, web_port=free_port()) as served, open_page(served.page_url) as page:
        up_s, load_s, end_col = _time_loading(page, max_load_s)
        out = {"viewer_up_s": round(up_s, 1), "load_s": round(load_s, 1), "load_avg": load_avg}
        if not play:
            return out
        out.update(_time_playing(page, end_col, max_play_s))
        page.press("Home")
        time.sleep(3 * POLL_S)
        home = cursor_column(_image(page.png()))
        page.press("End")
        time.sleep(3 * POLL_S)
        end = cursor_column(_image(page.png()))
        page.run_command("end of timeline")
        time.sleep(3 * POLL_S)
        palette = cursor_column(_image(page.png()))
        out.update(cursor_after_home=home, cursor_after_end=end, cursor_after_palette=palette, curves_end=end_col,
                   end_key_moves_to_end=end is not None and end >= end_col - 2,
                   palette_moves_to_end=palette is not None and palette >= end_col - 2)
    return out


def region(img: np.ndarray, box: tuple[float, float, float, float]) -> np.ndarray:
    h, w, _ = img.shape
    x0, x1, y0, y1 = box
    return img[int(y0 * h):int(y1 * h), int(x0 * w):int(x1 * w)]


def cloud_mask(img: np.ndarray) -> np.ndarray:
    """Pixels (H, W) of the run view within 45 of a cloud colour in every channel."""
    r = region(img, RUN_VIEW).astype(int)
    return np.any(np.abs(r[:, :, None, :] - CLOUD_COLOURS[None, None]).max(axis=3) < 45, axis=2)


def particle_pixels(img: np.ndarray) -> int:
    """Pixels of the run view inside a drawn particle: in a cloud colour together with their eight
    neighbours. A particle is a dot about 4 pixels across; an ellipsoid's wireframe, in the same
    colours, is a line too thin to have such pixels (0 in shots with ellipsoids and no particle).
    A cloud seen as a needle one or two pixels wide (the first steps after an IOD, along the line
    of sight) has almost none either (0-2 measured): this counts spread clouds' particles."""
    r = region(img, RUN_VIEW).astype(int)
    total = 0
    for colour in CLOUD_COLOURS:
        m = np.abs(r - colour).max(axis=2) < 45
        inner = m[1:-1, 1:-1].copy()
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                inner &= m[dy:dy + m.shape[0] - 2, dx:dx + m.shape[1] - 2]
        total += int(inner.sum())
    return total


def cloud_spread(mask: np.ndarray) -> float:
    """How far the cloud's pixels spread over the run view: between their 5th and 95th percentile
    columns as a fraction of its width, or rows as a fraction of its height, whichever is more
    (0 without pixels)."""
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return 0.0
    return max(float(np.percentile(xs, 95) - np.percentile(xs, 5)) / mask.shape[1],
               float(np.percentile(ys, 95) - np.percentile(ys, 5)) / mask.shape[0])


def raised_fraction(img: np.ndarray) -> float:
    """Of the position panel's columns that hold a curve, the fraction whose highest curve pixel
    is above the panel's bottom quarter (a linear axis flattens a decreasing error onto it)."""
    r = region(img, POSITION_PANEL).astype(int)
    coloured = (r.max(axis=2) - r.min(axis=2)) > 60
    cols = np.nonzero(coloured.any(axis=0))[0]
    if cols.size == 0:
        return 0.0
    top = np.array([np.nonzero(coloured[:, c])[0].min() for c in cols])
    return float(np.mean(top < 0.75 * r.shape[0]))


if __name__ == "__main__":
    import json
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from tests.recorders import viewer_shots

    from PIL import Image

    args = sys.argv[1:]
    if not args or args[0] in ("-h", "--help") or (len(args) < 2 and "--load-only" not in args):
        print("usage: viewer_shots.py RUN.rrd OUTDIR [--timing]   (start, middle and end pictures)\n"
              "       viewer_shots.py RUN.rrd --load-only          (load time only, as JSON)", file=sys.stderr)
        sys.exit(0 if args and args[0] in ("-h", "--help") else 2)
    if "--load-only" in sys.argv[2:]:  # viewer_shots.py RUN.rrd --load-only: load times only, no pictures
        print(json.dumps(viewer_shots.timings(sys.argv[1], play=False)), flush=True)
        sys.exit(0)
    if "--timing" in sys.argv[3:]:
        print(json.dumps(viewer_shots.timings(sys.argv[1])), flush=True)
    for name, png in viewer_shots.take(sys.argv[1], sys.argv[2]).items():
        # 256 colours: a quarter of the size, no visible change for the README
        Image.open(png).convert("RGB").quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(png, optimize=True)
        print(name, png)
