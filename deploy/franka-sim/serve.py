#!/usr/bin/env python3
"""franka-sim's FCI server (MuJoCo, FR3, server version 10) on 127.0.0.1.

franka-sim's own launcher binds the single-arm server to every interface;
phri's tests must reach nothing beyond this machine. This starts the same
server class bound to 127.0.0.1, without the gripper, enforcing the
communication constraints (20 lost commands abort the motion, as a real
control box does). FR3_MJCF must name the model (deploy/franka-sim/install
builds it). Usage: serve.py [--port P]
"""

import argparse
import logging
import os
import sys


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=1337, help="TCP command port (default 1337)")
    args = parser.parse_args()
    if not os.environ.get("FR3_MJCF"):
        print("serve.py: FR3_MJCF is not set (deploy/franka-sim/install builds the model)", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.WARNING, format="franka-sim: %(levelname)s %(name)s: %(message)s")
    from franka_sim import FrankaSimServer

    server = FrankaSimServer(
        host="127.0.0.1",
        port=args.port,
        enable_gripper=False,
        enforce_comm_constraints=True,
    )
    print(f"franka-sim: FCI server on 127.0.0.1:{args.port}", flush=True)
    try:
        server.start()
    except KeyboardInterrupt:
        pass
    finally:
        stop = getattr(server, "stop", None)
        if callable(stop):
            stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
