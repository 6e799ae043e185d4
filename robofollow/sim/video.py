"""Writing frames to mp4 files (H.264 through PyAV), one frame at a time."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import av
import numpy as np
from PIL import Image, ImageDraw, ImageFont

CODEC = "libx264"
CODEC_NAME = "h264"  # the format the encoder writes
PIXEL_FORMAT = "yuv420p"
# ultrafast keeps encoding at ~1 ms per 320x240 frame (veryfast: ~1.5 ms, 18% slower dataset
# generation on two cores, for files about half the size); a keyframe every 2 frames (as
# LeRobot's own encoder) makes random access by training data loaders cheap.
DATASET_OPTIONS = {"preset": "ultrafast", "crf": "23", "g": "2"}


class VideoEncoder:
    """An H.264 mp4 being written: `add(frame)` per (H, W, 3) uint8 frame, then `close()`.

    Width and height are padded to even sizes (yuv420p needs them). One encoding thread, so the
    bytes are the same on every run and workers do not compete for cores.
    """

    def __init__(self, path: str | Path, width: int, height: int, fps: int,
                 options: dict[str, str] | None = None):
        self.width, self.height, self.frames = width, height, 0
        self.container = av.open(str(path), mode="w")
        self.stream = self.container.add_stream(CODEC, rate=fps, options=options or {})
        self.stream.width, self.stream.height = width + width % 2, height + height % 2
        self.stream.pix_fmt = PIXEL_FORMAT
        self.stream.thread_count = 1

    def add(self, frame: np.ndarray) -> None:
        if frame.shape != (self.height, self.width, 3):
            raise ValueError(f"frame of shape {frame.shape}, expected "
                             f"{(self.height, self.width, 3)}")
        if self.height % 2 or self.width % 2:
            frame = np.pad(frame, ((0, self.height % 2), (0, self.width % 2), (0, 0)))
        self.container.mux(self.stream.encode(av.VideoFrame.from_ndarray(frame, format="rgb24")))
        self.frames += 1

    def close(self) -> None:
        self.container.mux(self.stream.encode())
        self.container.close()


CAPTION_HEIGHT = 28  # px: the band under a captioned frame


def captioned(frame: np.ndarray, text: str, step: int) -> np.ndarray:
    """The frame over a dark band that gives the text (cut with an ellipsis where it does not
    fit) and the step: what a viewer of an episode's video needs to know at every frame."""
    width = frame.shape[1]
    band = Image.new("RGB", (width, CAPTION_HEIGHT), (24, 24, 24))
    draw = ImageDraw.Draw(band)
    font = ImageFont.load_default()
    counter = f"step {step}"
    room = width - 16 - draw.textlength(counter, font=font) - 12
    shown = text or "(no instruction)"
    while draw.textlength(shown, font=font) > room and len(shown) > 1:
        shown = shown[:-2] + "…"
    draw.text((8, 8), shown, fill=(240, 240, 240), font=font)
    draw.text((width - 8 - draw.textlength(counter, font=font), 8), counter,
              fill=(180, 180, 180), font=font)
    return np.concatenate([frame, np.asarray(band)], axis=0)


def write_video(path: str | Path, frames: list[np.ndarray], fps: int) -> None:
    """Encode a list of (H, W, 3) uint8 frames."""
    height, width = frames[0].shape[:2]
    encoder = VideoEncoder(path, width, height, fps)
    for frame in frames:
        encoder.add(frame)
    encoder.close()


def read_frames(path: str | Path) -> list[np.ndarray]:
    """Every frame of a video, decoded to (H, W, 3) uint8 RGB."""
    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]


def concatenate(sources: list[Path], target: Path) -> None:
    """Join mp4 files of one encoding into one, without re-encoding: each file's packets are
    shifted by the duration of the files before it."""
    with av.open(str(sources[0])) as first, av.open(str(target), mode="w") as output:
        stream = output.add_stream_from_template(first.streams.video[0])
        offset = 0
        for source in sources:
            with av.open(str(source)) as container:
                video = container.streams.video[0]
                if video.time_base != stream.time_base:
                    raise ValueError(f"{source}: time base {video.time_base}, expected "
                                     f"{stream.time_base}")
                end = 0
                for packet in container.demux(video):
                    if packet.dts is None:  # the demuxer's end-of-stream marker
                        continue
                    end = max(end, packet.pts + packet.duration)
                    packet.pts += offset
                    packet.dts += offset
                    packet.stream = stream
                    output.mux(packet)
                offset += end


@dataclass(frozen=True)
class VideoProbe:
    width: int
    height: int
    fps: float  # the stream's average frame rate
    times: list[float]  # presentation times (s) of the frames, in order


def probe(path: str | Path) -> VideoProbe:
    """A video's size, frame rate and frame times, read from its stream and packets in one
    pass (nothing is decoded)."""
    with av.open(str(path)) as container:
        video = container.streams.video[0]
        times = sorted(float(packet.pts * video.time_base) for packet in container.demux(video)
                       if packet.dts is not None)
        return VideoProbe(video.codec_context.width, video.codec_context.height,
                          float(video.average_rate or 0), times)
