#!/usr/bin/env python3
"""Writes a random kinematic tree URDF (revolute, continuous, prismatic and fixed joints, arbitrary
origins and axes, box/cylinder/sphere collision) for the model tests:
python3 tests/reference/gen_tree.py SEED > crates/model/tests/data/tree_prismatic.urdf"""
import random
import sys

rng = random.Random(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
n_links = 12
kinds = ["revolute", "prismatic", "continuous", "revolute", "fixed"]
out = ['<?xml version="1.0"?>', f'<robot name="tree_{sys.argv[1] if len(sys.argv) > 1 else 1}">']


def v3(lo, hi):
    return " ".join(f"{rng.uniform(lo, hi):.6f}" for _ in range(3))


def inertial():
    a, b, c = (rng.uniform(0.01, 0.1) for _ in range(3))
    m = rng.uniform(0.3, 3.0)
    return (f'<inertial><origin xyz="{v3(-0.1, 0.1)}" rpy="{v3(-3, 3)}"/><mass value="{m:.4f}"/>'
            f'<inertia ixx="{b + c:.5f}" ixy="0" ixz="0" iyy="{a + c:.5f}" iyz="0" izz="{a + b:.5f}"/></inertial>')


geoms = ['<box size="0.1 0.05 0.2"/>', '<cylinder radius="0.04" length="0.3"/>', '<sphere radius="0.05"/>']
out.append(f'  <link name="base">{inertial()}</link>')
for i in range(1, n_links):
    parent = "base" if i == 1 else f"l{rng.randrange(0, i) or 1}" if rng.random() < 0.4 else f"l{i - 1}"
    if i == 1:
        kind = "revolute"
    else:
        kind = kinds[(i * 7 + rng.randrange(5)) % 5]
    out.append(f'  <link name="l{i}">{inertial()}<collision><origin xyz="{v3(-0.05, 0.05)}" rpy="{v3(-1, 1)}"/>'
               f'<geometry>{geoms[i % 3]}</geometry></collision></link>')
    lim = '<limit lower="-2" upper="2" effort="50" velocity="2"/>' if kind in ("revolute", "prismatic") else '<limit effort="50" velocity="2"/>'
    out.append(f'  <joint name="j{i}" type="{kind}"><parent link="{parent}"/><child link="l{i}"/>'
               f'<origin xyz="{v3(-0.3, 0.3)}" rpy="{v3(-3, 3)}"/><axis xyz="{v3(-1, 1)}"/>{lim}</joint>')
out.append("</robot>")
print("\n".join(out))
