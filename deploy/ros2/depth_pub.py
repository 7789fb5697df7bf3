#!/usr/bin/env python3
"""A ROS 2 depth camera stand-in on Eclipse Cyclone DDS (not ROS, not
RustDDS), for phri-camera-ros2's tests: publishes recorded depth frames
(headerless little-endian uint16 640x480 millimetres, 0 = no reading) as
`sensor_msgs/Image` with their `sensor_msgs/CameraInfo` before each, at a
rate, for a time, then prints one JSON object of what it published.

  depth_pub.py --frames DIR --duration S [--rate HZ] [--encoding E]
               [--width W --height H] [--domain D] [--image-topic T]
               [--info-topic T] [--fx F] [--age S] [--step-delta N]
               [--bigendian] [--no-info]

Frames are upsampled (or downsampled) by nearest neighbour to W x H; the
CameraInfo's K is the recording's (f = 580, c = (320, 240) at 640x480)
scaled to W x H with pixel centres at integers: f' = f s, c' = (c + 0.5) s
- 0.5. `32FC1` publishes metres with NaN for no reading; `rgb8` publishes a
colour image of the same size (a refused encoding). Stamps are the wall
clock at publication minus --age. --fx overrides K[0] (0: a refused
CameraInfo); --step-delta adds N (negative: a row too short) to the step.
"""
import argparse
import array
import json
import math
import os
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array as idl_array
from cyclonedds.idl.types import float64, int32, sequence, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic


# the types peer.py (the bridge's test peer, beside this file) defines,
# its Image reading and writing `data` as bytes in one copy
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer import Header, Image, Time  # noqa: E402


@dataclass
class RegionOfInterest(IdlStruct, typename="sensor_msgs::msg::dds_::RegionOfInterest_"):
    x_offset: uint32
    y_offset: uint32
    height: uint32
    width: uint32
    do_rectify: bool


@dataclass
class CameraInfo(IdlStruct, typename="sensor_msgs::msg::dds_::CameraInfo_"):
    header: Header
    height: uint32
    width: uint32
    distortion_model: str
    d: sequence[float64]
    k: idl_array[float64, 9]
    r: idl_array[float64, 9]
    p: idl_array[float64, 12]
    binning_x: uint32
    binning_y: uint32
    roi: RegionOfInterest



# the recording's intrinsics at 640x480 (data/kinect-person/README.md)
F, CX, CY = 580.0, 320.0, 240.0
SRC_W, SRC_H = 640, 480


def load(directory):
    frames = []
    for name in sorted(os.listdir(directory)):
        path = os.path.join(directory, name)
        if not name.startswith("depth-data-") or not os.path.isfile(path):
            continue
        a = array.array("H")
        with open(path, "rb") as f:
            a.frombytes(f.read())
        if len(a) != SRC_W * SRC_H:
            sys.exit(f"depth_pub.py: {path}: {len(a)} samples, not {SRC_W}x{SRC_H}")
        if sys.byteorder == "big":
            a.byteswap()
        frames.append(a)
    if not frames:
        sys.exit(f"depth_pub.py: no depth-data-* frames in {directory}")
    return frames


def resized(src, w, h):
    """Nearest neighbour: output (x, y) takes source (x*640//w, y*480//h)."""
    if (w, h) == (SRC_W, SRC_H):
        return src
    xs = [x * SRC_W // w for x in range(w)]
    out = array.array("H")
    for y in range(h):
        row = src[(y * SRC_H // h) * SRC_W:(y * SRC_H // h + 1) * SRC_W]
        out.extend(row[x] for x in xs)
    return out


def encoded(mm, encoding, big):
    """The image's data and bytes per pixel."""
    if encoding in ("16UC1", "mono16"):
        a = array.array("H", mm)
        bpp = 2
    elif encoding == "32FC1":
        a = array.array("f", (v / 1000.0 if v else math.nan for v in mm))
        bpp = 4
    elif encoding == "rgb8":
        return bytes(3 * len(mm)), 3
    else:
        sys.exit(f"depth_pub.py: --encoding {encoding}: 16UC1, mono16, 32FC1 or rgb8")
    if big != (sys.byteorder == "big"):
        a.byteswap()
    return a.tobytes(), bpp


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", required=True, help="directory of depth-data-* frames")
    ap.add_argument("--duration", type=float, required=True, help="seconds to publish")
    ap.add_argument("--rate", type=float, default=30.0, help="images per second")
    ap.add_argument("--encoding", default="16UC1", help="16UC1, mono16, 32FC1 or rgb8")
    ap.add_argument("--width", type=int, default=SRC_W)
    ap.add_argument("--height", type=int, default=SRC_H)
    ap.add_argument("--domain", type=int, default=0)
    ap.add_argument("--image-topic", default="/camera/camera/depth/image_rect_raw")
    ap.add_argument("--info-topic", default="/camera/camera/depth/camera_info")
    ap.add_argument("--fx", type=float, help="K[0] of the CameraInfo instead of the scaled 580")
    ap.add_argument("--age", type=float, default=0.0, help="stamp this many seconds in the past")
    ap.add_argument("--step-delta", type=int, default=0, help="added to each image's step")
    ap.add_argument("--bigendian", action="store_true", help="big-endian samples")
    ap.add_argument("--no-info", action="store_true", help="publish no CameraInfo")
    ap.add_argument("--start-after", type=float, default=0.0,
                    help="seconds to wait (discovery) before the first image")
    a = ap.parse_args()
    w, h = a.width, a.height
    sx, sy = w / SRC_W, h / SRC_H
    t_load = time.monotonic()
    frames = [encoded(resized(f, w, h), a.encoding, a.bigendian) for f in load(a.frames)]
    load_s = time.monotonic() - t_load
    k = [F * sx, 0.0, (CX + 0.5) * sx - 0.5, 0.0, F * sy, (CY + 0.5) * sy - 0.5, 0.0, 0.0, 1.0]
    if a.fx is not None:
        k[0] = a.fx
    p = [k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0]

    dp = DomainParticipant(a.domain)
    qos = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(1))
    images = DataWriter(dp, Topic(dp, "rt" + a.image_topic, Image), qos=qos)
    infos = DataWriter(dp, Topic(dp, "rt" + a.info_topic, CameraInfo), qos=qos)
    time.sleep(a.start_after)
    period = 1.0 / a.rate
    t0 = time.monotonic()
    n, tick = 0, t0
    write_s = 0.0
    while time.monotonic() - t0 < a.duration:
        data, bpp = frames[n % len(frames)]
        stamp = time.time_ns() - int(a.age * 1e9)
        header = Header(stamp=Time(sec=stamp // 1_000_000_000, nanosec=stamp % 1_000_000_000),
                        frame_id="camera_depth_optical_frame")
        t_w = time.monotonic()
        if not a.no_info:
            infos.write(CameraInfo(header=header, height=h, width=w, distortion_model="plumb_bob",
                                   d=[0.0] * 5, k=k, r=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], p=p,
                                   binning_x=0, binning_y=0,
                                   roi=RegionOfInterest(0, 0, 0, 0, False)))
        images.write(Image(header=header, height=h, width=w, encoding=a.encoding,
                           is_bigendian=1 if a.bigendian else 0,
                           step=w * bpp + a.step_delta, data=data))
        write_s += time.monotonic() - t_w
        n += 1
        tick += period
        delay = tick - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        else:
            tick = time.monotonic()  # behind: no burst
    span = time.monotonic() - t0
    print(json.dumps({
        "published": n,
        "rate_hz": n / span if span > 0 else None,
        "frames": len(frames),
        "width": w,
        "height": h,
        "encoding": a.encoding,
        "k": k,
        "load_s": round(load_s, 3),
        "write_ms_mean": round(1000.0 * write_s / n, 3) if n else None,
    }))


if __name__ == "__main__":
    main()
