#!/usr/bin/env python3
"""An independent ROS 2 peer of phri-ros2, on Eclipse Cyclone DDS (not ROS,
not RustDDS): subscribes to the bridge's DDS topics with ROS 2's type names
and QoS, optionally publishes /phri/request texts at given times, and prints
one JSON object of what it received: per topic the count, the rate over the
span it received them, the latency from the message's header stamp to its
arrival (both ROS time, this host's clock), and samples of the content.

  peer.py --duration S [--request T:TEXT ...] [--request-after PHASE+S:TEXT ...] [--linger S] [--positions FILE] [--domain D]

--positions writes every /joint_states' positions, one line each (Python's
repr of each float: the exact double), for comparison with robot/state.
--topics humans reads ROS4HRI's /humans/bodies/tracked (hri_msgs/IdsList):
the lists of ids as they changed; tf gives the newest transform of each
child frame besides the frames' names.
"""
import argparse
import json
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, float64, int32, sequence, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64]
    effort: sequence[float64]


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3
    torque: Vector3


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header
    wrench: Wrench


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped]


@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header
    height: uint32
    width: uint32
    encoding: str
    is_bigendian: uint8
    step: uint32
    data: sequence[uint8]


def read_as_bytes(cls, member):
    """Read a sequence<uint8> member of `cls` as bytes, in one copy: the
    binding's own machine builds a list of ints (6 ms for a 640x480 depth
    image, 0.15 ms as bytes), which a subscriber at 30 Hz cannot afford
    beside a cell on 2 cores. The wire format and the type's XTypes
    description stay sequence<uint8>; unchanged if the binding differs."""
    from cyclonedds.idl._machinery import BytesMachine
    cls.__idl__.populate()
    for machine in (cls.__idl__.v1_machine, cls.__idl__.v2_machine):
        members = getattr(machine, "members_machines", None)
        if members is not None and member in members:
            members[member] = BytesMachine()


read_as_bytes(Image, "data")


@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level: uint8
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header
    status: sequence[DiagnosticStatus]


@dataclass
class IdsList(IdlStruct, typename="hri_msgs::msg::dds_::IdsList_"):
    header: Header
    ids: sequence[str]


BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(4000))
RELIABLE = Qos(Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)), Policy.History.KeepLast(100))


def take(reader, n):
    """Up to n samples of the reader, without the invalid ones (a writer's
    end or disposal: no data)."""
    return [m for m in reader.take(N=n) if type(m).__name__ != "InvalidSample"]


def stamp_ns(h):
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def percentile(xs, p):
    if not xs:
        return None
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(p / 100.0 * len(xs)))]


class Seen:
    """What arrived on one topic: arrival times [ns] and latencies [µs]."""

    def __init__(self):
        self.arrivals = []
        self.latency_us = []
        self.stamps = []

    def add(self, header):
        now = time.time_ns()
        self.arrivals.append(now)
        self.stamps.append(stamp_ns(header))
        self.latency_us.append((now - stamp_ns(header)) / 1000.0)

    def summary(self):
        n = len(self.arrivals)
        span = (self.arrivals[-1] - self.arrivals[0]) / 1e9 if n > 1 else 0.0
        # the longest stretch without a silence over 0.2 s (a restart of
        # the bridge, rediscovery): its rate
        best, start = (0, 0), 0
        for i in range(1, n + 1):
            if i == n or self.arrivals[i] - self.arrivals[i - 1] > 200_000_000:
                if i - start > best[1] - best[0]:
                    best = (start, i)
                start = i
        a, b = best
        steady = (self.arrivals[b - 1] - self.arrivals[a]) / 1e9 if b - a > 1 else 0.0
        stamps = sorted(self.stamps)
        stamped = (stamps[-1] - stamps[0]) / 1e9 if n > 1 else 0.0
        window = sorted(self.stamps[a:b])
        return {
            "count": n,
            "rate_hz": (n - 1) / span if span > 0 else None,
            "steady_rate_hz": (b - a - 1) / steady if steady > 0 else None,
            # that stretch by the messages' stamps: how many arrived, and
            # the first and last stamp [ns, ROS time], so that a reader can
            # count what was published in the same span
            "steady": {
                "count": b - a,
                "first_stamp_ns": window[0] if window else None,
                "last_stamp_ns": window[-1] if window else None,
            },
            "silences": sum(1 for i in range(1, n) if self.arrivals[i] - self.arrivals[i - 1] > 200_000_000),
            # the rate the messages were published at, from their stamps
            "stamped_rate_hz": (n - 1) / stamped if stamped > 0 else None,
            "latency_us": {
                "p50": percentile(self.latency_us, 50),
                "p99": percentile(self.latency_us, 99),
                "max": max(self.latency_us) if self.latency_us else None,
            },
        }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, required=True, help="seconds to listen")
    ap.add_argument("--request", action="append", default=[], metavar="T:TEXT",
                    help="publish TEXT on /phri/request T s after the start")
    ap.add_argument("--request-after", action="append", default=[], metavar="PHASE+S:TEXT",
                    help="publish TEXT on /phri/request S s after /phri/status first showed PHASE")
    ap.add_argument("--linger", type=float, default=None, metavar="S",
                    help="stop S s after the last request was sent (before --duration)")
    ap.add_argument("--positions", help="write every /joint_states' positions here")
    ap.add_argument("--domain", type=int, default=0)
    ap.add_argument("--topics", default="joint_states,tf,status,contact_force,depth",
                    help="comma-separated topics to read (default: all of them but humans)")
    a = ap.parse_args()
    requests = []
    for r in a.request:
        t, _, text = r.partition(":")
        try:
            requests.append((float(t), text))
        except ValueError:
            sys.exit(f"peer.py: --request {r!r}: not T:TEXT")
    requests.sort()
    after = []
    for r in a.request_after:
        cond, _, text = r.partition(":")
        phase, _, delay = cond.partition("+")
        try:
            after.append((phase, float(delay or 0), text))
        except ValueError:
            sys.exit(f"peer.py: --request-after {r!r}: not PHASE+S:TEXT")
    phase_seen = {}

    dp = DomainParticipant(a.domain)
    readers = {
        "joint_states": DataReader(dp, Topic(dp, "rt/joint_states", JointState), qos=BEST_EFFORT),
        "tf": DataReader(dp, Topic(dp, "rt/tf", TFMessage), qos=BEST_EFFORT),
        "status": DataReader(dp, Topic(dp, "rt/phri/status", DiagnosticArray), qos=RELIABLE),
        "contact_force": DataReader(dp, Topic(dp, "rt/phri/contact_force", WrenchStamped), qos=BEST_EFFORT),
        "depth": DataReader(dp, Topic(dp, "rt/phri/depth", Image), qos=Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(2))),
        "humans": DataReader(dp, Topic(dp, "rt/humans/bodies/tracked", IdsList), qos=RELIABLE),
    }
    wanted = set(a.topics.split(","))
    unknown = wanted - set(readers)
    if unknown:
        sys.exit(f"peer.py: --topics: unknown {sorted(unknown)} (known: {sorted(readers)})")
    readers = {k: r for k, r in readers.items() if k in wanted}
    writer = DataWriter(dp, Topic(dp, "rt/phri/request", String), qos=RELIABLE)
    seen = {k: Seen() for k in readers}
    names, frames, status_last, depth_shape = None, set(), None, None
    transforms, id_lists = {}, []
    max_force, phases = 0.0, []
    positions = open(a.positions, "w") if a.positions else None
    sent = []
    t0 = time.monotonic()
    while time.monotonic() - t0 < a.duration:
        t = time.monotonic() - t0
        if a.linger is not None and sent and not requests and not after \
                and t > sent[-1]["t_s"] + a.linger:
            break
        while requests and requests[0][0] <= t:
            _, text = requests.pop(0)
            writer.write(String(data=text))
            sent.append({"t_s": round(t, 3), "text": text})
        for item in list(after):
            phase, delay, text = item
            if phase in phase_seen and t >= phase_seen[phase] + delay:
                after.remove(item)
                writer.write(String(data=text))
                sent.append({"t_s": round(t, 3), "text": text})
        got = 0
        for m in take(readers["joint_states"], 4000) if "joint_states" in readers else []:
            got += 1
            seen["joint_states"].add(m.header)
            names = list(m.name)
            if positions:
                positions.write(" ".join(repr(x) for x in m.position) + "\n")
        for m in take(readers["tf"], 1000) if "tf" in readers else []:
            got += 1
            for tr in m.transforms:
                frames.add((tr.header.frame_id, tr.child_frame_id))
                t, q = tr.transform.translation, tr.transform.rotation
                transforms[tr.child_frame_id] = {
                    "parent": tr.header.frame_id,
                    "stamp_ns": stamp_ns(tr.header),
                    "t": [t.x, t.y, t.z],
                    "q": [q.x, q.y, q.z, q.w],
                }
            if m.transforms:
                seen["tf"].add(m.transforms[0].header)
        for m in take(readers["status"], 100) if "status" in readers else []:
            got += 1
            seen["status"].add(m.header)
            if m.status:
                status_last = {kv.key: kv.value for kv in m.status[0].values}
                status_last["level"] = m.status[0].level
                p = status_last.get("phase")
                if p and (not phases or phases[-1] != p):
                    phases.append(p)
                if p:
                    phase_seen.setdefault(p, time.monotonic() - t0)
        for m in take(readers["contact_force"], 1000) if "contact_force" in readers else []:
            got += 1
            seen["contact_force"].add(m.header)
            f = m.wrench.force
            max_force = max(max_force, (f.x * f.x + f.y * f.y + f.z * f.z) ** 0.5)
        for m in take(readers["depth"], 10) if "depth" in readers else []:
            got += 1
            seen["depth"].add(m.header)
            depth_shape = [m.width, m.height, m.encoding, len(m.data)]
        for m in take(readers["humans"], 100) if "humans" in readers else []:
            got += 1
            seen["humans"].add(m.header)
            ids = list(m.ids)
            if not id_lists or id_lists[-1] != ids:
                id_lists.append(ids)
        if not got:
            time.sleep(0.0005)
    if positions:
        positions.close()
    out = {k: s.summary() for k, s in seen.items()}
    extra = {
        "joint_states": {"names": names},
        "tf": {"frames": sorted(f"{p}>{c}" for p, c in frames), "last": transforms},
        "status": {"last": status_last, "phases": phases},
        "contact_force": {"max_force_n": max_force},
        "depth": {"last": depth_shape},
        "humans": {"lists": id_lists},
    }
    for k in out:
        out[k].update(extra[k])
    out["requests_sent"] = sent
    print(json.dumps(out))


if __name__ == "__main__":
    main()
