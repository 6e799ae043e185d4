"""Where a demonstration's camera frames go while the expert runs: mp4 encoders (LeRobot) or
raw uint8 arrays in HDF5. Both keep the running image statistics LeRobot stores (its
quantiles included)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from pathlib import Path

import numpy as np

from robofollow.data.stats import QUANTILE_KEYS, counted_quantiles
from robofollow.sim.cameras import CAMERA_NAMES
from robofollow.sim.video import DATASET_OPTIONS, VideoEncoder

STATS_SIDE = 80  # px: images are subsampled to about this size for their statistics
STATS_EVERY = 4  # statistics use every 4th frame (LeRobot, too, samples frames for them)


def image_key(camera: str) -> str:
    return f"observation.images.{camera}"


class ImageStats:
    """LeRobot's image statistics, per channel, values scaled to [0, 1]: min, max, mean, std
    and the quantiles q01 .. q99, over every STATS_EVERY-th frame (the first included), pixels
    subsampled to about STATS_SIDE px (LeRobot, too, computes them on sampled, downsampled
    frames).

    The quantiles come from a count of each channel's 256 pixel values (one np.bincount per
    sampled frame) and are exact for those pixels: numpy's inverted-CDF quantile of the
    counts (`stats.counted_quantiles`: the smallest value with at least q * pixels at or below
    it), / 255. LeRobot approximates the same quantile from a 5000-bin histogram of the uint8
    values, interpolating inside a bin, so on the same pixels its figure lies within one of
    its bins (1 / 5000 of the value range: at most 2e-4 after scaling) of this one."""

    def __init__(self, width: int, height: int):
        self.stride = max(1, max(width, height) // STATS_SIDE)
        self.seen, self.frames, self.count = 0, 0, 0
        self.total, self.squares = np.zeros(3), np.zeros(3)
        self.low, self.high = np.full(3, np.inf), np.full(3, -np.inf)
        self.histogram = np.zeros((3, 256), dtype=np.int64)  # [channel, pixel value]: pixels

    def add(self, image: np.ndarray) -> None:
        self.seen += 1
        if (self.seen - 1) % STATS_EVERY:
            return
        sample = image[::self.stride, ::self.stride].reshape(-1, 3)
        pixels = sample.astype(np.float64) / 255.0
        self.frames += 1
        self.count += len(pixels)
        self.total += pixels.sum(axis=0)
        self.squares += np.square(pixels).sum(axis=0)
        self.low, self.high = np.minimum(self.low, pixels.min(0)), np.maximum(self.high, pixels.max(0))
        for channel in range(3):
            self.histogram[channel] += np.bincount(sample[:, channel], minlength=256)

    def result(self) -> dict:
        mean = self.total / self.count
        std = np.sqrt(np.maximum(self.squares / self.count - np.square(mean), 0.0))
        estimates = counted_quantiles(self.histogram) / 255.0  # [quantile, channel]
        return {"min": self.low.tolist(), "max": self.high.tolist(), "mean": mean.tolist(),
                "std": std.tolist(), "count": self.frames,
                **dict(zip(QUANTILE_KEYS, estimates.tolist(), strict=True))}


class FrameSink(ABC):
    """Takes each recorded frame's camera images; the last frame is dropped on close (a
    dataset frame pairs an observation with the *next* action, so the final observation has
    none)."""

    def __init__(self, width: int, height: int):
        self.pending: dict[str, np.ndarray] | None = None
        self.stats = {camera: ImageStats(width, height) for camera in CAMERA_NAMES}
        self.frames = 0

    def __call__(self, images: dict[str, np.ndarray]) -> None:
        if self.pending is not None:
            for camera in CAMERA_NAMES:
                self.stats[camera].add(self.pending[camera])
            self.write(self.pending)
            self.frames += 1
        self.pending = images

    @abstractmethod
    def write(self, images: dict[str, np.ndarray]) -> None: ...

    @abstractmethod
    def close(self) -> None: ...

    def image_stats(self) -> dict[str, dict]:
        return {image_key(camera): self.stats[camera].result() for camera in CAMERA_NAMES}


class VideoSink(FrameSink):
    """One mp4 per camera: `<folder>/observation.images.<camera>.mp4`."""

    def __init__(self, folder: Path, width: int, height: int, fps: int):
        super().__init__(width, height)
        self.encoders = {camera: VideoEncoder(folder / f"{image_key(camera)}.mp4", width, height,
                                              fps, DATASET_OPTIONS) for camera in CAMERA_NAMES}

    def write(self, images: dict[str, np.ndarray]) -> None:
        for camera, encoder in self.encoders.items():
            encoder.add(images[camera])

    def close(self) -> None:
        for encoder in self.encoders.values():
            encoder.close()


class ArraySink(FrameSink):
    """Raw (T, H, W, 3) uint8 arrays `observations/images/<camera>` in an open HDF5 file,
    one compressed chunk per frame."""

    def __init__(self, h5file, width: int, height: int):
        super().__init__(width, height)
        group = h5file.require_group("observations/images")
        self.datasets = {camera: group.create_dataset(
            camera, shape=(0, height, width, 3), maxshape=(None, height, width, 3),
            dtype=np.uint8, chunks=(1, height, width, 3), compression="lzf")
            for camera in CAMERA_NAMES}

    def write(self, images: dict[str, np.ndarray]) -> None:
        for camera, dataset in self.datasets.items():
            dataset.resize(self.frames + 1, axis=0)
            dataset[self.frames] = images[camera]

    def close(self) -> None:
        pass
