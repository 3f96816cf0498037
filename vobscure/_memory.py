"""How much memory a request needs, how much there is, and the refusal of what cannot fit.

One place for the library's memory arithmetic: :func:`available_bytes` (what the system and the
process's control group allow now), :func:`format_bytes` (for messages), :func:`require` (refuse,
before any work, a request whose estimate exceeds :data:`MEMORY_FRACTION` of what is available)
and the per-stage models below. Each model is bytes per pixel plus fixed bytes, calibrated on
tracemalloc peaks of the Cornell box (``benchmarks/bench_memory.py`` prints each stage's
measured peak beside the model's estimate; ``tests/test_memory.py`` checks that the model does
not under-estimate them by more than :data:`MODEL_UNDER`).

The figure of memory available can be set with the environment variable
``VOBSCURE_MEMORY_LIMIT`` (bytes, an integer): it then replaces what the system says (tests use
it to see refusals without a big machine; a user can use it to keep a job within a share).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["MemoryBudgetError", "available_bytes", "format_bytes", "require", "Need", "MEMORY_FRACTION",
           "ENV_LIMIT", "MODEL_UNDER", "gbuffer_need", "lazy_images_need", "reference_need",
           "estimator_need", "render_job_need", "compare_need", "count_items",
           "estimate_job_need", "require_estimate"]

#: A request is refused when its estimate exceeds this fraction of the memory available: the
#: rest is left for what the models do not count (the interpreter, Embree's scene, the page
#: cache other processes need) and for their error (at most :data:`MODEL_UNDER` under).
MEMORY_FRACTION = 0.8
#: The environment variable that, set to a number of bytes, replaces the memory available.
ENV_LIMIT = "VOBSCURE_MEMORY_LIMIT"
#: The largest under-estimate of a measured peak the models allow (0.2: the model may say
#: 80 % of a measured peak, never less); ``tests/test_memory.py`` holds them to it. With it,
#: an accepted request (estimate <= MEMORY_FRACTION x available) has a true peak of at most
#: estimate / (1 - MODEL_UNDER) <= available whenever MEMORY_FRACTION <= 1 - MODEL_UNDER.
MODEL_UNDER = 0.2
#: A cgroup limit at or above this is "no limit" (cgroup v1 writes 2**63 rounded to a page).
_UNLIMITED = 1 << 60

_MEMINFO = Path("/proc/meminfo")
_CGROUP_V2 = Path("/sys/fs/cgroup")
_CGROUP_V1 = Path("/sys/fs/cgroup/memory")
_PROC_CGROUP = Path("/proc/self/cgroup")


class MemoryBudgetError(ValueError):
    """A request needs more memory than is available. A ValueError, so the command prints its
    one-line message and exits with status 2; the message says how much it needs, how much is
    available and what to reduce."""


def format_bytes(n) -> str:
    """A byte count for people: ``512 B``, ``16 KiB``, ``37.3 GiB``.

    Examples
    --------
    >>> format_bytes(512), format_bytes(16384), format_bytes(40 * 2**30)
    ('512 B', '16 KiB', '40 GiB')
    """
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{int(n)} B" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1024
    raise AssertionError("unreachable")  # pragma: no cover


def _read_int(path: Path) -> int | None:
    """The integer in a one-line file ("max" and unreadable files: None)."""
    try:
        text = path.read_text().strip()
    except (OSError, UnicodeDecodeError):
        return None
    try:
        return int(text)
    except ValueError:
        return None


def _meminfo_available(path: Path = None) -> int | None:
    """MemAvailable of ``/proc/meminfo``, in bytes (None when absent)."""
    try:
        lines = (path or _MEMINFO).read_text().splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    for line in lines:
        if line.startswith("MemAvailable:"):
            parts = line.split()
            try:
                value = int(parts[1])
            except (IndexError, ValueError):
                return None
            unit = parts[2].lower() if len(parts) > 2 else "b"
            return value * {"kb": 1024, "mb": 1024 ** 2, "gb": 1024 ** 3}.get(unit, 1)
    return None


def _cgroup_room() -> int | None:
    """Bytes the process's memory control group still allows (limit - usage), None when no
    limit is set: cgroup v2 ``memory.max - memory.current``, v1 ``memory.limit_in_bytes -
    memory.usage_in_bytes``, read in the process's own group (``/proc/self/cgroup``) and at the
    hierarchy's root (what a container shows of its own group); the smallest room found."""
    v2_dirs, v1_dirs = [_CGROUP_V2], [_CGROUP_V1]
    try:
        lines = _PROC_CGROUP.read_text().splitlines()
    except (OSError, UnicodeDecodeError):
        lines = []
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        group = parts[2].strip().lstrip("/")
        if parts[0] == "0" and parts[1] == "":
            v2_dirs.insert(0, _CGROUP_V2 / group)
        elif "memory" in parts[1].split(","):
            v1_dirs.insert(0, _CGROUP_V1 / group)
    rooms = []
    for dirs, limit_name, usage_name in ((v2_dirs, "memory.max", "memory.current"),
                                         (v1_dirs, "memory.limit_in_bytes", "memory.usage_in_bytes")):
        for directory in dirs:
            limit = _read_int(directory / limit_name)
            if limit is not None and limit < _UNLIMITED:
                rooms.append(max(0, limit - (_read_int(directory / usage_name) or 0)))
    return min(rooms) if rooms else None


def available_bytes() -> int | None:
    """Bytes of memory this process can use now; None where the system does not say.

    :data:`ENV_LIMIT` (``VOBSCURE_MEMORY_LIMIT``), when set, is the answer. Otherwise, on Linux,
    the smaller of ``MemAvailable`` (``/proc/meminfo``) and the room left under the process's
    memory control group limit (cgroup v2 ``memory.max - memory.current``, v1
    ``memory.limit_in_bytes - memory.usage_in_bytes``; :func:`_cgroup_room`) when one is set; elsewhere the free
    physical pages (``os.sysconf``).

    Raises
    ------
    ValueError
        If ``VOBSCURE_MEMORY_LIMIT`` is set but is not a non-negative integer.
    """
    override = os.environ.get(ENV_LIMIT)
    if override is not None and override.strip():
        try:
            value = int(override.strip())
        except ValueError:
            value = -1
        if value < 0:
            raise ValueError(f"{ENV_LIMIT} must be a number of bytes (an integer >= 0), got {override!r}")
        return value
    found = [v for v in (_meminfo_available(), _cgroup_room()) if v is not None]
    if found:
        return min(found)
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


@dataclass(frozen=True)
class Need:
    """An estimate of peak memory: ``per_pixel`` bytes for each pixel plus ``fixed`` bytes."""

    per_pixel: float
    fixed: float = 0.0

    def __add__(self, other: "Need") -> "Need":
        return Need(self.per_pixel + other.per_pixel, self.fixed + other.fixed)

    def __mul__(self, k: float) -> "Need":
        return Need(self.per_pixel * k, self.fixed * k)

    __rmul__ = __mul__

    def bytes(self, pixels: int) -> int:
        """The bytes for an image of ``pixels`` pixels."""
        return int(math.ceil(self.per_pixel * pixels + self.fixed))

    def max(self, other: "Need", pixels: int) -> "Need":
        """The larger of the two at ``pixels`` pixels."""
        return self if self.bytes(pixels) >= other.bytes(pixels) else other


def require(need: Need, *, size, what: str, reduce: str) -> None:
    """Refuse (raise :class:`MemoryBudgetError`) a request of ``need`` on a ``size`` = (W, H)
    image when it exceeds :data:`MEMORY_FRACTION` of :func:`available_bytes`; nothing when it
    fits or when the memory available is unknown.

    ``what`` names the work ("rendering a 512 x 512 G-buffer"), ``reduce`` the options to
    reduce ("--size"); the message adds the need, the bytes a pixel, the memory available and
    the largest image of the same shape that would fit.
    """
    available = available_bytes()
    W, H = (int(v) for v in size)
    pixels = W * H
    needed = need.bytes(pixels)
    if available is None or needed <= MEMORY_FRACTION * available:
        return
    room = (MEMORY_FRACTION * available - need.fixed) / need.per_pixel if need.per_pixel > 0 else 0.0
    scale = math.sqrt(max(room, 0.0) / pixels)
    fit_w, fit_h = int(W * scale), int(H * scale)
    fit = (f"at most about {fit_w} x {fit_h} here" if fit_w >= 1 and fit_h >= 1
           else "no image size fits here: free some memory")
    raise MemoryBudgetError(f"{what} needs about {format_bytes(needed)} ({need.per_pixel:.0f} bytes a pixel"
                            + (f" + {format_bytes(need.fixed)}" if need.fixed >= 1 << 20 else "")
                            + f"); {format_bytes(available)} are available (refused above "
                            f"{MEMORY_FRACTION:.0%} of it, {ENV_LIMIT} overrides the figure): reduce {reduce} ({fit})")


# --------------------------------------------------------------------------- per-stage models
# Bytes per pixel and fixed bytes, from tracemalloc peaks of the Cornell box at 128 x 128 and
# 256 x 256 on 2 threads (per pixel = the slope between the two sizes, fixed = the rest),
# rounded up; ``benchmarks/bench_memory.py`` re-measures them.

#: render_gbuffer, one layer: the depth, normal, valid and primitive images and the per-hit
#: data kept for the lazy images (measured 162 B at 128^2, 178 B at 256^2, 2 threads).
GBUFFER_PIXEL = 190
#: Each layer beyond the first: float32 depth, int32 triangle, bool entering (9 B), plus one
#: float32 front and back slot (8 B) for each layer (the slots are at most the layers) and
#: 1 B for the first layer (measured K = 4: 220 B a pixel + 1.8 MB on 2 threads).
LAYER_PIXEL = 17
#: The peeling's temporaries, per thread and per layer (chunks of ``PEEL_RAYS`` rays; the
#: threads' chunks overlap differently from run to run: K = 4 at 128^2 measured 300-371 B a
#: pixel, so 1.8-2.9 MB above the per-pixel part on 2 threads).
PEEL_THREAD_LAYER = 3 << 17
#: Every lazy world- and view-space image of a rendered G-buffer and its hit data (measured
#: 224 B a pixel at 128^2 and 256^2).
LAZY_PIXEL = 232
#: A ray-cast reference (ambient_occlusion, obscurance, sky) per pixel: its sample shifts,
#: value, stderr and the points' arrays (measured 197-264 B a pixel), and per thread its
#: chunk of rays (5-10 MB on 2 threads).
RAYCAST_PIXEL = 280
RAYCAST_THREAD = 6 << 20
#: The world-space VO (volumetric, shell) per pixel, and per thread its chunk of ball points
#: with their inside votes (measured 267-277 B a pixel + 65-68 MB on 2 threads).
VOLUME_PIXEL = 280
VOLUME_THREAD = 36 << 20
#: The converged screen-space VO (vo_reference at its default 448 segments, with the exact
#: pixels' plane tables, depth pyramids and the tests of their candidates in chunks of 512
#: pixels): measured peaks 3.6, 17.9, 37.1, 75.4 and 181.8 MB at 48^2, 128^2, 256^2, 400^2 and
#: 1280 x 720 (tracemalloc, Cornell box, compare's radius and twice it): at most 1.6 KB a pixel
#: at 48^2, under 600 B a pixel from 256^2; 600 B a pixel + 20 MB covers every size measured
#: (1.5-6x). With the candidates' tests in chunks of 4096 pixels and the float32 kernel's four
#: rays at once, 1280 x 720: 237 and 248 MB inside the Cornell box, 230 and 253 MB inside the
#: atrium, at compare's radius and twice it (tracemalloc): the model is 2.3-2.5x above.
SCREEN_REFERENCE_PIXEL = 600
SCREEN_REFERENCE_FIXED = 20 << 20
#: The largest screen-space estimator's peak (gtao, vbao, point:33, area: 16-41 B a pixel
#: above a chunk of 4.5-11 MB), output included.
ESTIMATOR_PIXEL = 48
ESTIMATOR_FIXED = 12 << 20
#: What a kept image costs: an estimate (float64) and a reference (value and stderr).
IMAGE_PIXEL = 8
REFERENCE_KEPT_PIXEL = 16
#: ``vobscure render``'s outputs: the PNG images and the archive's copies.
RENDER_OUTPUT_PIXEL = 120
#: One frame of ``vobscure estimate`` read and converted: the file's float32 channels (16 B)
#: and ``GBuffer.from_arrays``' peak (1.6 x its 17-byte output: 27 B), rounded up. The whole
#: one-frame job measured 68 B a pixel + 1.4 MB (line:9 at 128^2 and 256^2, after a warm-up).
FRAME_PIXEL = 48
#: compare's plots and metrics (error maps, thin-feature masks, the gallery's panels) per
#: kept image, and its figures: an allowance, not measured alone (matplotlib's canvas is
#: outside tracemalloc's view); the whole compare job is measured with it.
PLOT_PIXEL = 24
PLOT_FIXED = 64 << 20


def count_items(spec) -> int:
    """The number of items of a comma-separated string or a sequence (1 for anything else)."""
    if isinstance(spec, str):
        return max(1, len([k for k in spec.split(",") if k.strip()]))
    try:
        return max(1, len(spec))
    except TypeError:
        return 1


def _threads(threads) -> int:
    if threads is None:
        from .raytrace import default_threads

        return default_threads()
    return max(1, int(threads))


def gbuffer_need(layers: int = 1, *, threads=None) -> Need:
    """render_gbuffer's peak with ``layers`` surfaces a pixel (its result included)."""
    K = max(1, int(layers))
    if K == 1:
        return Need(GBUFFER_PIXEL)
    return Need(GBUFFER_PIXEL + LAYER_PIXEL * K, PEEL_THREAD_LAYER * K * _threads(threads))


def lazy_images_need() -> Need:
    """Every lazy world- and view-space image of a rendered G-buffer, with its hit data."""
    return Need(LAZY_PIXEL)


def reference_need(kind: str, *, threads=None) -> Need:
    """The transient peak of computing a reference, its result included: ``kind`` is
    ``"screen"`` (the converged screen-space VO) or the ground truth's quantity
    (``"volumetric"``, ``"ao"``, ``"obscurance"``; the reference registry's
    ``Reference.ground_truth``)."""
    if kind == "screen":
        return Need(SCREEN_REFERENCE_PIXEL, SCREEN_REFERENCE_FIXED)
    if kind == "volumetric":
        return Need(VOLUME_PIXEL, VOLUME_THREAD * _threads(threads))
    return Need(RAYCAST_PIXEL, RAYCAST_THREAD * _threads(threads))


def estimator_need() -> Need:
    """The largest screen-space estimator's peak, its output included."""
    return Need(ESTIMATOR_PIXEL, ESTIMATOR_FIXED)


def render_job_need(quantity: str, *, threads=None) -> Need:
    """``vobscure render``: the G-buffer with its lazy images, the ground truth's peak and
    the outputs."""
    return gbuffer_need(1) + lazy_images_need() + reference_need(quantity, threads=threads) \
        + Need(RENDER_OUTPUT_PIXEL)


def estimate_job_need(frames: int, *, flicker_reference: bool = False) -> Need:
    """``vobscure estimate`` of ``frames`` frames: a frame read while the last is held, the
    estimator (or, with ``flicker_reference``, the converged screen-space VO, the larger), and
    with several frames every frame's visibility (and reference) kept and stacked at the end
    for the flicker (measured: 4 frames with a 64-sample flicker reference, 548-560 B a pixel)."""
    transient = reference_need("screen") if flicker_reference else estimator_need()
    kept = 2 * IMAGE_PIXEL * frames * (2 if flicker_reference else 1) if frames > 1 else 0
    return Need(FRAME_PIXEL + kept) + transient


def require_estimate(frames: int, *, flicker_reference: bool, size) -> None:
    """:func:`require` of :func:`estimate_job_need` with the command's words."""
    W, H = (int(v) for v in size)
    require(estimate_job_need(frames, flicker_reference=flicker_reference), size=size,
            what=f"estimating {frames} frame(s) of {W} x {H}" + (" with a flicker reference" if flicker_reference else ""),
            reduce="the frames given (--depth)" + (" or --flicker-reference 0" if flicker_reference else ""))


def compare_need(*, references, configs: int, radii: int = 1, layers: int = 1, frames: int = 0,
                 frame_configs: int = 0, orbit: int = 0, plots: bool = True, threads=None,
                 pixels: int = 1) -> Need:
    """compare()'s whole job: what it keeps (the G-buffer and its lazy images, every
    reference per radius, every estimate per configuration and radius, with ``frames`` the
    references of every frame and each sequence configuration's history) plus the largest
    transient (a reference, an estimator, a layered G-buffer, or another frame's G-buffer).
    ``references``: the kinds of :func:`reference_need`, one per reference."""
    refs = tuple(references)
    kept = gbuffer_need(1) + lazy_images_need() + Need(REFERENCE_KEPT_PIXEL * len(refs) * radii) \
        + Need(IMAGE_PIXEL * configs * radii)
    if layers > 1:
        kept = kept + gbuffer_need(layers, threads=threads)
    if frames > 1:
        # every frame's references and, per sequence configuration, its history and outputs
        kept = kept + Need(REFERENCE_KEPT_PIXEL * len(refs) * frames + 4 * IMAGE_PIXEL * frame_configs)
    if plots:
        kept = kept + Need(PLOT_PIXEL * (configs + len(refs)) * radii, PLOT_FIXED)
    transient = estimator_need()
    for name in refs:
        transient = transient.max(reference_need(name, threads=threads), pixels)
    if frames > 1 or orbit > 1:
        # another view's G-buffer, lazy images and converged screen-space VO at once
        transient = transient.max(gbuffer_need(1) + lazy_images_need() + reference_need("screen"), pixels)
    return kept + transient
