#!/usr/bin/env python3
"""franka-sim's FCI server (MuJoCo, FR3, server version 10) on 127.0.0.1.

franka-sim's own launcher binds the single-arm server to every interface;
phri's tests must reach nothing beyond this machine. This starts the same
server class bound to 127.0.0.1, without the gripper, enforcing the
communication constraints (20 lost commands abort the motion, as a real
control box does). FR3_MJCF must name the model (deploy/franka-sim/install
builds it).

Two things it adds around franka-sim's own classes, neither touching the
wire protocol or the physics:

* One physics step per state sent (default; --free-running turns it off).
  franka-sim steps MuJoCo on a timer of its own, unsynchronised with the
  states it sends: on a loaded machine one state carries up to 6 ms of
  motion while its message_id says 1 ms. A real control box samples the arm
  exactly once per message_id. Here the state stream drives the physics, so
  message_id is the arm's clock again (when no client is connected the arm
  keeps its own 1 kHz timer).
* --forces-port P: contact forces from phri's simulated person (phri-sim in
  the hybrid cell, sim.forces_to) arrive as UDP datagrams on 127.0.0.1:P and
  act on the named bodies through MuJoCo's xfrc_applied, so phri's collision
  detection is checked against this physics engine. A datagram replaces the
  forces of the one before; none for 50 ms clears them.

* --rt-priority N (default 0: none): the server's threads run SCHED_FIFO
  at N where permitted. On the torque loop's CPU it needs none (the loop's
  real-time work is light), and at 50 it starved the services starting
  there (a controller not yet real-time missed its start-up heartbeat).

* --cpus LIST (default 1): the CPUs it runs on, where present: the torque
  loop's in deploy/phri.toml, where phri's real-time work is light (on
  perception's CPU its states and commands waited for depth frames).

Usage: serve.py [--port P] [--forces-port P] [--free-running] [--rt-priority N] [--cpus LIST]
"""

import argparse
import logging
import os
import socket
import struct
import sys
import threading
import time

#: a forces datagram: magic, count, then per force a body name (32 bytes,
#: UTF-8, zero padded), the point [m] and the force [N], world frame (f64 LE)
FORCES_MAGIC = b"PHRF"
FORCE_RECORD = struct.Struct("<32s3d3d")
MAX_FORCES = 16
#: a force larger than this is refused as garbage [N] (a hand walking into
#: the moving arm is pushed back with a kilonewton or more by the person's
#: contact model)
MAX_FORCE_N = 10000.0
#: forces older than this are dropped [s]
FORCES_TIMEOUT_S = 0.05
#: without a state stream for this long the arm runs on its own timer [s]
STREAM_IDLE_S = 0.5

_stream = threading.local()


def lockstep_class(base):
    import mujoco
    import numpy as np

    class LockstepSim(base):
        """franka-sim's MuJoCo FR3, stepped once per state its stream sends."""

        def __init__(self, lockstep: bool, forces_sock):
            super().__init__(enable_vis=False)
            self._lockstep = lockstep
            self._step_lock = threading.Lock()
            self._driven = 0.0
            self._forces_sock = forces_sock
            self._forces = []  # (body id, point, force)
            self._forces_at = 0.0
            self.forces_refused = 0

        # -- the state stream drives the physics ---------------------------

        def get_robot_state(self):
            if self._lockstep and getattr(_stream, "active", False):
                with self._step_lock:
                    self._one_step()
                    self._driven = time.perf_counter()
            return self._state_snapshot

        def _one_step(self):
            self._apply_control()
            self._apply_forces()
            mujoco.mj_step(self.model, self.data)
            self._read_and_publish_state()

        def run_simulation(self):
            next_step = time.perf_counter()
            while self.running:
                with self._step_lock:
                    if not self._lockstep or time.perf_counter() - self._driven > STREAM_IDLE_S:
                        self._one_step()
                next_step += self.dt
                now = time.perf_counter()
                if next_step > now:
                    time.sleep(next_step - now)
                elif now - next_step > self.dt:
                    next_step = now

        # -- the person's contact forces -----------------------------------

        def _apply_forces(self):
            xfrc = self.data.xfrc_applied
            xfrc[:] = 0.0
            if self._forces_sock is None:
                return
            while True:
                try:
                    datagram = self._forces_sock.recv(4 + 4 + MAX_FORCES * FORCE_RECORD.size + 1)
                except BlockingIOError:
                    break
                forces = self._parse(datagram)
                if forces is None:
                    self.forces_refused += 1
                    continue
                self._forces, self._forces_at = forces, time.perf_counter()
            if time.perf_counter() - self._forces_at > FORCES_TIMEOUT_S:
                self._forces = []
            for body, point, force in self._forces:
                xfrc[body, :3] += force
                xfrc[body, 3:] += np.cross(point - self.data.xipos[body], force)

        def _parse(self, datagram):
            if len(datagram) < 8 or datagram[:4] != FORCES_MAGIC:
                return None
            (n,) = struct.unpack_from("<I", datagram, 4)
            if n > MAX_FORCES or len(datagram) != 8 + n * FORCE_RECORD.size:
                return None
            forces = []
            for k in range(n):
                name, px, py, pz, fx, fy, fz = FORCE_RECORD.unpack_from(datagram, 8 + k * FORCE_RECORD.size)
                values = (px, py, pz, fx, fy, fz)
                if not all(np.isfinite(v) for v in values) or max(abs(v) for v in values[3:]) > MAX_FORCE_N:
                    return None
                body = mujoco.mj_name2id(
                    self.model, mujoco.mjtObj.mjOBJ_BODY, self.prefix + name.rstrip(b"\0").decode("utf-8", "replace")
                )
                if body < 0:
                    return None
                forces.append((body, np.array(values[:3]), np.array(values[3:])))
            return forces

    return LockstepSim


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=1337, help="TCP command port (default 1337)")
    parser.add_argument(
        "--forces-port", type=int, default=0, help="UDP port on 127.0.0.1 for contact forces (default: none)"
    )
    parser.add_argument(
        "--free-running", action="store_true", help="franka-sim's own physics timer, not one step per state"
    )
    parser.add_argument(
        "--rt-priority",
        type=int,
        default=0,
        help="SCHED_FIFO priority of the server's threads where permitted (default 0: none)",
    )
    parser.add_argument(
        "--cpus", default="1", help="comma-separated CPUs to run on, where present (default 1; '': any)"
    )
    args = parser.parse_args()
    if not 0 <= args.rt_priority <= 99:
        print(f"serve.py: --rt-priority {args.rt_priority} is not in 0..=99", file=sys.stderr)
        return 2
    if not os.environ.get("FR3_MJCF"):
        print("serve.py: FR3_MJCF is not set (deploy/franka-sim/install builds the model)", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.WARNING, format="franka-sim: %(levelname)s %(name)s: %(message)s")
    if args.cpus:
        try:
            wanted = {int(c) for c in args.cpus.split(",")}
        except ValueError:
            print(f"serve.py: --cpus {args.cpus!r} is not a list of CPU numbers", file=sys.stderr)
            return 2
        present = wanted & os.sched_getaffinity(0)
        if present:
            os.sched_setaffinity(0, present)
        else:
            print(f"franka-sim: none of CPUs {args.cpus} here: running on any", file=sys.stderr)
    if args.rt_priority:
        # before any thread starts: they inherit it
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(args.rt_priority))
        except (PermissionError, OSError) as e:
            print(f"franka-sim: SCHED_FIFO {args.rt_priority} refused ({e}): running without", file=sys.stderr)
    from franka_sim import FrankaSimServer
    from franka_sim.mujoco_franka_sim import MujocoFrankaSim
    from franka_sim.server.state_stream import StateStreamMixin

    # mark the thread that streams states: its reads step the physics
    transmit = StateStreamMixin.start_robot_state_transmission

    def marked(self, *a, **k):
        _stream.active = True
        return transmit(self, *a, **k)

    StateStreamMixin.start_robot_state_transmission = marked

    forces_sock = None
    if args.forces_port:
        forces_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            forces_sock.bind(("127.0.0.1", args.forces_port))
        except OSError as e:
            print(f"serve.py: --forces-port {args.forces_port}: {e}", file=sys.stderr)
            return 2
        forces_sock.setblocking(False)

    sim = lockstep_class(MujocoFrankaSim)(lockstep=not args.free_running, forces_sock=forces_sock)
    server = FrankaSimServer(
        host="127.0.0.1",
        port=args.port,
        enable_gripper=False,
        enforce_comm_constraints=True,
        physics_sim=sim,
    )
    extra = f", contact forces on udp 127.0.0.1:{args.forces_port}" if args.forces_port else ""
    print(f"franka-sim: FCI server on 127.0.0.1:{args.port}{extra}", flush=True)
    try:
        server.start()
    except KeyboardInterrupt:
        pass
    finally:
        stop = getattr(server, "stop", None)
        if callable(stop):
            stop()
        if sim.forces_refused:
            print(f"franka-sim: {sim.forces_refused} forces datagram(s) refused (malformed, unknown body or over {MAX_FORCE_N:.0f} N)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
