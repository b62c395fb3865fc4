#!/usr/bin/env python3
"""Golden forward-kinematics values for the vendored URDF robots.

For each robot vendored under robots/ (Franka Panda, Universal Robots UR5, both
from the example-robot-data package; see robots/README.md) this script

  * loads the URDF with Pinocchio (pinocchio.buildModelFromUrdf),
  * takes the serial chain from the base link to the tip link by walking the
    model's parent chain from the tip frame (joints off that path, e.g. the
    Panda's prismatic finger joints, are left at Pinocchio's neutral value and
    are not part of the chain),
  * draws 100 configurations with a fixed seed, each chain joint uniform
    within its URDF position limits ([-pi, pi] for continuous joints or
    joints without finite limits),
  * computes forward kinematics and writes robots/golden/<robot>_fk.csv:
    a header row, then one row per configuration:
        q_<joint>                       n joint values, radians, base to tip
        <joint>_px,_py,_pz              each moving joint's frame origin
        <joint>_ax,_ay,_az              and its axis (unit vector)
        tip_px,tip_py,tip_pz            the tip frame's origin
        tip_r00 .. tip_r22              the tip frame's rotation, row-major
    everything expressed in the base link's frame, metres; a joint's frame is
    the URDF joint frame (= its child link's frame), i.e. Pinocchio's
    data.oMi, and its axis is the joint axis rotated into the base frame;
  * writes robots/golden/<robot>_chain.txt: the URDF, base and tip link, the
    chain's joint names in order, their limits, the seed and the versions.

Numbers are printed with repr(float), the shortest string that round-trips
to the same float64 exactly.

As an independent cross-check the same poses are recomputed with a plain
numpy chain product straight from the URDF XML (xml.etree; origin xyz/rpy with
R = Rz(yaw) Ry(pitch) Rx(roll), joint rotation about the axis by Rodrigues'
formula) and must agree with Pinocchio to 1e-12 for every configuration; the
XML walk must also find the same moving joints in the same order.  This
guards against taking the wrong chain or misreading a frame.

This script shares no code with the Rust crates of this repository; it is
the reference they are tested against.  It is deterministic: running it
twice gives byte-identical files.

Regenerate (from the repository root):

    python3 robots/golden/urdf_fk.py

Made with Python 3.11.7 and the PyPI packages (pip install example-robot-data pin):
    pin 4.1.0 (Pinocchio), numpy 2.4.6, example-robot-data 6.0.0
(example-robot-data is only the source of the vendored files: the script reads
the copies under robots/, not the installed package).
"""

import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
ROBOTS_DIR = os.path.dirname(HERE)
REPO = os.path.dirname(ROBOTS_DIR)

SAMPLES = 100
TOL = 1e-12

# name, URDF (relative to robots/), base link, tip link candidates (first
# present wins), RNG seed.
ROBOTS = [
    ("panda", "panda_description/urdf/panda_collision.urdf", "panda_link0",
     ["panda_link8", "panda_hand"], 20240601),
    ("ur5", "ur_description/urdf/ur5_robot.urdf", "base_link",
     ["tool0", "ee_link"], 20240602),
]

LOCAL_AXIS = {
    "JointModelRX": np.array([1.0, 0.0, 0.0]),
    "JointModelRY": np.array([0.0, 1.0, 0.0]),
    "JointModelRZ": np.array([0.0, 0.0, 1.0]),
}


def fmt(x):
    return repr(float(x))


# ---------------------------------------------------------------- URDF XML side

def parse_vec(text, default):
    if text is None:
        return np.array(default, dtype=float)
    v = [float(s) for s in text.split()]
    assert len(v) == 3, text
    return np.array(v, dtype=float)


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_matrix(rpy):
    roll, pitch, yaw = rpy
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def rodrigues(axis, angle):
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)


def homogeneous(r, p):
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = p
    return t


class XmlJoint:
    def __init__(self, el):
        self.name = el.get("name")
        self.type = el.get("type")
        self.parent = el.find("parent").get("link")
        self.child = el.find("child").get("link")
        origin = el.find("origin")
        xyz = parse_vec(origin.get("xyz") if origin is not None else None, [0, 0, 0])
        rpy = parse_vec(origin.get("rpy") if origin is not None else None, [0, 0, 0])
        self.origin = homogeneous(rpy_matrix(rpy), xyz)
        axis = el.find("axis")
        a = parse_vec(axis.get("xyz") if axis is not None else None, [1, 0, 0])
        self.axis = a / np.linalg.norm(a)
        lim = el.find("limit")
        lo = float(lim.get("lower", "0")) if lim is not None else 0.0
        hi = float(lim.get("upper", "0")) if lim is not None else 0.0
        if self.type == "continuous" or not (math.isfinite(lo) and math.isfinite(hi)) or lo >= hi:
            lo, hi = -math.pi, math.pi
        self.limits = (lo, hi)

    @property
    def moving(self):
        return self.type != "fixed"


def xml_chain(urdf_path, base, tip):
    """Joints (fixed ones included) on the path base -> tip, from the XML."""
    root = ET.parse(urdf_path).getroot()
    by_child = {}
    for el in root.findall("joint"):
        j = XmlJoint(el)
        assert j.child not in by_child, "link %s has two parent joints" % j.child
        by_child[j.child] = j
    links = [el.get("name") for el in root.findall("link")]
    path = []
    link = tip
    while link != base:
        assert link in by_child, "%s is not below %s" % (tip, base)
        j = by_child[link]
        path.append(j)
        link = j.parent
    path.reverse()
    return path, links


def xml_fk(path, q):
    """Joint origins and axes and the tip pose by a plain 4x4 chain product."""
    t = np.eye(4)
    origins, axes = [], []
    k = 0
    for j in path:
        t = t @ j.origin
        if j.moving:
            assert j.type in ("revolute", "continuous"), j.type
            origins.append(t[:3, 3].copy())
            axes.append(t[:3, :3] @ j.axis)
            t = t @ homogeneous(rodrigues(j.axis, q[k]), np.zeros(3))
            k += 1
    assert k == len(q)
    return origins, axes, t


# ------------------------------------------------------------- Pinocchio side

def pin_chain(model, base_id, tip_id):
    """Joint ids on the path base -> tip, walking parents from the tip frame."""
    chain = []
    j = model.frames[tip_id].parentJoint
    stop = model.frames[base_id].parentJoint
    while j != stop:
        assert j != 0, "base frame is not an ancestor of the tip frame"
        chain.append(j)
        j = model.parents[j]
    chain.reverse()
    return chain


def local_axis(jm):
    name = jm.shortname()
    if name in LOCAL_AXIS:
        return LOCAL_AXIS[name]
    if name == "JointModelRevoluteUnaligned":
        a = np.array(jm.extract().axis, dtype=float)
        return a / np.linalg.norm(a)
    raise ValueError("chain joint of unsupported type %s" % name)


def run(name, rel_urdf, base, tip_candidates, seed):
    urdf = os.path.join(ROBOTS_DIR, rel_urdf)
    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()

    tips = [t for t in tip_candidates if model.existFrame(t, pin.FrameType.BODY)]
    assert tips, "none of %s in %s" % (tip_candidates, rel_urdf)
    tip = tips[0]
    assert model.existFrame(base, pin.FrameType.BODY), base
    base_id = model.getFrameId(base, pin.FrameType.BODY)
    tip_id = model.getFrameId(tip, pin.FrameType.BODY)

    chain = pin_chain(model, base_id, tip_id)
    names = [model.names[j] for j in chain]
    for j in chain:
        assert model.nqs[j] == 1 and model.nvs[j] == 1, model.names[j]

    path, links = xml_chain(urdf, base, tip)
    xml_moving = [j for j in path if j.moving]
    assert [j.name for j in xml_moving] == names, ([j.name for j in xml_moving], names)

    limits = [j.limits for j in xml_moving]
    for j, (lo, hi) in zip(chain, limits):
        i = model.idx_qs[j]
        # Pinocchio reads the same URDF limits (continuous joints would differ, nq = 2).
        assert model.lowerPositionLimit[i] == lo and model.upperPositionLimit[i] == hi, model.names[j]

    rng = np.random.default_rng(seed)
    header = ["q_" + n for n in names]
    for n in names:
        header += [n + s for s in ("_px", "_py", "_pz", "_ax", "_ay", "_az")]
    header += ["tip_px", "tip_py", "tip_pz"]
    header += ["tip_r%d%d" % (r, c) for r in range(3) for c in range(3)]

    rows = []
    worst = 0.0
    for _ in range(SAMPLES):
        qc = np.array([rng.uniform(lo, hi) for lo, hi in limits])
        q = pin.neutral(model)
        for j, v in zip(chain, qc):
            q[model.idx_qs[j]] = v
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        o_m_b = data.oMf[base_id]
        row = list(qc)
        p_origins, p_axes = [], []
        for j in chain:
            b_m_i = o_m_b.actInv(data.oMi[j])
            p = np.array(b_m_i.translation)
            a = np.array(b_m_i.rotation) @ local_axis(model.joints[j])
            assert abs(np.linalg.norm(a) - 1.0) < 1e-14
            p_origins.append(p)
            p_axes.append(a)
            row += list(p) + list(a)
        b_m_t = o_m_b.actInv(data.oMf[tip_id])
        tp = np.array(b_m_t.translation)
        tr = np.array(b_m_t.rotation)
        row += list(tp) + list(tr.reshape(9))

        # Independent cross-check from the XML.
        x_origins, x_axes, x_tip = xml_fk(path, qc)
        diffs = [np.max(np.abs(x_tip[:3, 3] - tp)), np.max(np.abs(x_tip[:3, :3] - tr))]
        diffs += [np.max(np.abs(a - b)) for a, b in zip(x_origins, p_origins)]
        diffs += [np.max(np.abs(a - b)) for a, b in zip(x_axes, p_axes)]
        d = max(diffs)
        assert d <= TOL, "%s: Pinocchio and the XML chain differ by %g" % (name, d)
        worst = max(worst, d)
        rows.append(row)

    csv_path = os.path.join(HERE, name + "_fk.csv")
    with open(csv_path, "w", newline="\n") as f:
        f.write(",".join(header) + "\n")
        for row in rows:
            assert len(row) == len(header)
            f.write(",".join(fmt(x) for x in row) + "\n")

    others = [model.names[j] for j in range(1, model.njoints) if j not in chain]
    chain_path = os.path.join(HERE, name + "_chain.txt")
    with open(chain_path, "w", newline="\n") as f:
        f.write("# Written by robots/golden/urdf_fk.py; do not edit. Columns of %s_fk.csv.\n" % name)
        f.write("robot: %s\n" % name)
        f.write("urdf: robots/%s\n" % rel_urdf)
        f.write("base_link: %s\n" % base)
        f.write("tip_link: %s\n" % tip)
        f.write("tip_candidates: %s\n" % " ".join(tip_candidates))
        f.write("joints: %s\n" % " ".join(names))
        f.write("fixed_joints_on_path: %s\n" % " ".join(j.name for j in path if not j.moving))
        f.write("joints_not_in_chain: %s\n" % (" ".join(others) if others else "-"))
        f.write("samples: %d\n" % SAMPLES)
        f.write("seed: %d (numpy.random.default_rng, uniform per joint in chain order)\n" % seed)
        f.write("frame: every position and axis is in the base link's frame, metres\n")
        f.write("cross_check: numpy chain product from the URDF XML, max |diff| %s (tolerance %s)\n"
                % ("%.1e" % worst, TOL))
        f.write("versions: pin %s, numpy %s, python %d.%d.%d\n"
                % (pin.__version__, np.__version__, *sys.version_info[:3]))
        f.write("limits (name lower upper, radians):\n")
        for n, (lo, hi) in zip(names, limits):
            f.write("  %s %s %s\n" % (n, fmt(lo), fmt(hi)))
        f.write("links: %s\n" % " ".join(links))

    print("%s: %d joints %s, base %s, tip %s, %d rows, XML cross-check max |diff| %.1e -> %s"
          % (name, len(names), names, base, tip, len(rows), worst,
             os.path.relpath(csv_path, REPO)))


def main():
    for r in ROBOTS:
        run(*r)


if __name__ == "__main__":
    main()
