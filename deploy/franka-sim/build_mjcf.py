#!/usr/bin/env python3
"""Build the FR3 MJCF franka-sim runs from, offline.

franka-sim asks `robot_descriptions` for its FR3 model, which downloads it.
Offline, it runs from the FR3 URDF it bundles (franka_sim/models/fr3.urdf):
drop the mesh elements, let MuJoCo compile the URDF, save it as MJCF, and
give the joints the armature and damping the URDF lacks (without them the
idle arm's last joint spins up). Usage: build_mjcf.py OUT.xml
"""

import os
import re
import sys
import tempfile

import mujoco
import franka_sim

#: joint armature [kg m²] and viscous damping [Nm s/rad] of every FR3 joint
ARMATURE = 0.1
DAMPING = 1.0


def main() -> int:
    if len(sys.argv) != 2:
        print("usage: build_mjcf.py OUT.xml", file=sys.stderr)
        return 2
    out = sys.argv[1]
    urdf = os.path.join(os.path.dirname(franka_sim.__file__), "models", "fr3.urdf")
    with open(urdf, encoding="utf-8") as f:
        text = f.read()
    # no meshes: the arm's geometry is phri's business (its own capsules)
    text = re.sub(r"<visual\b.*?</visual>", "", text, flags=re.S)
    text = re.sub(r"<collision\b.*?</collision>", "", text, flags=re.S)
    text = text.replace(
        "</robot>",
        '<mujoco><compiler discardvisual="false" fusestatic="false"/></mujoco></robot>',
    )
    with tempfile.TemporaryDirectory() as tmp:
        stripped = os.path.join(tmp, "fr3.urdf")
        with open(stripped, "w", encoding="utf-8") as f:
            f.write(text)
        raw = os.path.join(tmp, "fr3.xml")
        mujoco.mj_saveLastXML(raw, mujoco.MjModel.from_xml_path(stripped))
        with open(raw, encoding="utf-8") as f:
            xml = f.read()
    # every hinge: the armature and damping the URDF lacks (its own few
    # mNm s/rad leave the idle arm's last joint free to spin up)
    def joint(m: "re.Match[str]") -> str:
        attrs = re.sub(r'\s(armature|damping)="[^"]*"', "", m.group(1))
        return f'<joint{attrs} armature="{ARMATURE}" damping="{DAMPING}"'

    xml = re.sub(r"<joint(\s[^>]*?)(?=/?>)", joint, xml)
    tmp_out = out + ".tmp"
    with open(tmp_out, "w", encoding="utf-8") as f:
        f.write(xml)
    # it must load as written
    mujoco.MjModel.from_xml_path(tmp_out)
    os.replace(tmp_out, out)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
