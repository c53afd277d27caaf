"""Current industrial arms from published numbers (the library's models; see :mod:`workcell.robots.library`).

Joint values, zero pose and directions are the manufacturer controller's, as the
ROS-Industrial descriptions and the published OPW parameter sets give them (UR arms: UR's
own DH). ``fk(q)`` is the flange (ROS ``tool0``: z out of the flange) in the robot's base
frame (ROS ``base_link``, on the floor under axis 1; UR: the DH base frame), so each
robot's ``tool`` is its flange until a gripper or tool is attached.

The industrial arms are built as their ROS-Industrial URDFs build them: each joint's
origin (a translation, m) from the previous link frame and its axis, every link frame
parallel to the base at q = 0 (:func:`urdf_joints`). The UR arms come from UR's DH table.
Speeds are the manufacturers' maximum joint speeds; accelerations and jerks are not
published and are derived by :func:`workcell.robots.library.derived_limits`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from workcell import spatial
from workcell.robots.chain import Joint, joints_from_table
from workcell.robots.robot import Robot

__all__ = [
    "abb_irb120",
    "abb_irb140",
    "abb_irb2400",
    "fanuc_lrmate200id",
    "kuka_kr6_r700",
    "kuka_kr16",
    "ur3e",
    "ur5e",
    "ur10e",
    "urdf_joints",
]

_D = np.pi / 180
Row = tuple[str, tuple[float, float, float], tuple[float, float, float], tuple[float, float], float]
"""(name, origin xyz m, axis, limits (lo, hi) deg, max speed deg/s)."""
TOOL0 = spatial.rot_y(np.pi / 2)  # ROS-Industrial tool0: z out of a flange facing +x at q = 0


def urdf_joints(
    rows: Sequence[Row], accelerations: Sequence[float], jerks: Sequence[float]
) -> tuple[Joint, ...]:
    """Revolute joints from URDF-style rows; ``accelerations`` (rad/s^2), ``jerks`` (rad/s^3)."""
    return tuple(
        Joint(
            name,
            spatial.translation(*xyz),
            axis,
            limits=(lo * _D, hi * _D),
            max_speed=v * _D,
            max_acceleration=float(a),
            max_jerk=float(j),
        )
        for (name, xyz, axis, (lo, hi), v), a, j in zip(rows, accelerations, jerks, strict=True)
    )


def _arm(
    name: str, rows: Sequence[Row], tool: np.ndarray, home_deg: Sequence[float], source: str
) -> Robot:
    from workcell.robots.library import derived_limits

    acc, jerk = derived_limits([r[4] * _D for r in rows])
    return Robot(
        name=name,
        joints=urdf_joints(rows, acc, jerk),
        tool=tool,
        poses={"home": np.array(home_deg) * _D, "zero": np.zeros(len(rows))},
        source=source,
    )


# ---------------------------------------------------------------------------- UR
def _ur(
    name: str,
    d1: float,
    a2: float,
    a3: float,
    d4: float,
    d5: float,
    d6: float,
    speeds: Sequence[float],
    source: str,
) -> Robot:
    from workcell.robots.library import derived_limits

    table = [
        (0, d1, 90, 0),
        (a2, 0, 0, 0),
        (a3, 0, 0, 0),
        (0, d4, 90, 0),
        (0, d5, -90, 0),
        (0, d6, 0, 0),
    ]
    acc, jerk = derived_limits([v * _D for v in speeds])
    joints = joints_from_table(
        table,
        [(-360, 360)] * 6,
        max_speed_deg=speeds,
        max_acceleration_deg=[a / _D for a in acc],
        max_jerk_deg=[j / _D for j in jerk],
        names=["shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"],
    )
    home = np.array([0, -90, 90, -90, -90, 0]) * _D
    return Robot(name=name, joints=joints, poses={"home": home, "zero": np.zeros(6)}, source=source)


_UR_DH = (
    "UR's published DH table (Universal Robots, 'DH parameters for calculations of "
    "kinematics and dynamics', support article 45257, e-Series)"
)
_UR_SPEEDS = (
    "maximum joint speeds of the {} user manual (e-Series, as UR's ROS 2 description cites them)"
)


def ur3e() -> Robot:
    """Universal Robots UR3e: d1 0.15185, a2 -0.24355, a3 -0.2132, d4 0.13105, d5 0.08535,
    d6 0.0921 m; joints +-360 deg; speeds 180 (base, shoulder, elbow), 360 (wrists) deg/s;
    reach 500 mm. Sources: UR's DH table and the UR3e user manual."""
    src = f"{_UR_DH}; {_UR_SPEEDS.format('UR3e')}"
    return _ur(
        "ur3e",
        0.15185,
        -0.24355,
        -0.2132,
        0.13105,
        0.08535,
        0.0921,
        [180, 180, 180, 360, 360, 360],
        src,
    )


def ur5e() -> Robot:
    """Universal Robots UR5e: d1 0.1625, a2 -0.425, a3 -0.3922, d4 0.1333, d5 0.0997, d6
    0.0996 m; joints +-360 deg; speeds 180 deg/s on every joint; reach 850 mm. Sources:
    UR's DH table and the UR5e user manual."""
    src = f"{_UR_DH}; {_UR_SPEEDS.format('UR5e')}"
    return _ur("ur5e", 0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996, [180] * 6, src)


def ur10e() -> Robot:
    """Universal Robots UR10e: d1 0.1807, a2 -0.6127, a3 -0.57155, d4 0.17415, d5 0.11985,
    d6 0.11655 m; joints +-360 deg; speeds 120 (base, shoulder), 180 (elbow, wrists) deg/s;
    reach 1300 mm. Sources: UR's DH table and the UR10e user manual."""
    src = f"{_UR_DH}; {_UR_SPEEDS.format('UR10e')}"
    return _ur(
        "ur10e",
        0.1807,
        -0.6127,
        -0.57155,
        0.17415,
        0.11985,
        0.11655,
        [120, 120, 180, 180, 180, 180],
        src,
    )


# ---------------------------------------------------------------------------- KUKA
def kuka_kr6_r700() -> Robot:
    """KUKA KR 6 R700 sixx (KR AGILUS): the ROS-Industrial ``kuka_kr6_support``
    description (joint origins, axes, limits and speeds of KUKA's data sheet: A1 +-170,
    A2 -190..45, A3 -120..156, A4 +-185, A5 +-120, A6 +-350 deg; 360, 300, 360, 381, 388,
    615 deg/s); reach 706.7 mm. Its OPW parameters (a1 0.025, a2 -0.035, b 0, c1 0.400,
    c2 0.315, c3 0.365, c4 0.080 m, offsets (0, -90, 0, 0, 0, 0) deg, joints 1, 4, 6
    reversed) are the published set of Brandstötter et al. / opw_kinematics."""
    rows: list[Row] = [
        ("a1", (0, 0, 0.400), (0, 0, -1), (-170, 170), 360),
        ("a2", (0.025, 0, 0), (0, 1, 0), (-190, 45), 300),
        ("a3", (0.315, 0, 0), (0, 1, 0), (-120, 156), 360),
        ("a4", (0, 0, 0.035), (-1, 0, 0), (-185, 185), 381),
        ("a5", (0.365, 0, 0), (0, 1, 0), (-120, 120), 388),
        ("a6", (0.080, 0, 0), (-1, 0, 0), (-350, 350), 615),
    ]
    src = "ROS-Industrial kuka_kr6_support kr6r700sixx (KUKA data sheet limits and speeds); OPW set of opw_kinematics"
    return _arm("kuka_kr6_r700", rows, TOOL0, [0, -90, 90, 0, 90, 0], src)


def kuka_kr16() -> Robot:
    """KUKA KR 16-2: the ROS-Industrial ``kuka_kr16_support`` description ``kr16_2``
    (A1 at 0.675 m, a1 0.26, upper arm 0.68, forearm 0.67 with a 0.035 m drop, flange
    0.158 m; limits A1 +-185, A2 -155..35, A3 -130..154, A4 +-350, A5 +-130, A6 +-350 deg;
    speeds 156, 156, 156, 330, 330, 615 deg/s); reach 1611 mm."""
    rows: list[Row] = [
        ("a1", (0, 0, 0.675), (0, 0, -1), (-185, 185), 156),
        ("a2", (0.26, 0, 0), (0, 1, 0), (-155, 35), 156),
        ("a3", (0.68, 0, 0), (0, 1, 0), (-130, 154), 156),
        ("a4", (0.67, 0, -0.035), (-1, 0, 0), (-350, 350), 330),
        ("a5", (0, 0, 0), (0, 1, 0), (-130, 130), 330),
        ("a6", (0, 0, 0), (-1, 0, 0), (-350, 350), 615),
    ]
    tool = spatial.translation(0.158, 0, 0) @ TOOL0
    src = "ROS-Industrial kuka_kr16_support kr16_2 (KUKA KR 16-2 data sheet limits and speeds)"
    return _arm("kuka_kr16", rows, tool, [0, -90, 90, 0, 90, 0], src)


# ---------------------------------------------------------------------------- ABB
def abb_irb120() -> Robot:
    """ABB IRB 120-3/0.6: the ROS-Industrial ``abb_irb120_support`` description (axis 2
    at 0.29 m, upper arm 0.27, forearm 0.302 with a 0.07 m rise, flange 0.072 m; limits
    +-165, +-110, -110..70, +-160, +-120, +-400 deg; speeds 250, 250, 250, 320, 320, 420
    deg/s, the IRB 120 product specification's); reach 580 mm."""
    rows: list[Row] = [
        ("j1", (0, 0, 0), (0, 0, 1), (-165, 165), 250),
        ("j2", (0, 0, 0.29), (0, 1, 0), (-110, 110), 250),
        ("j3", (0, 0, 0.27), (0, 1, 0), (-110, 70), 250),
        ("j4", (0, 0, 0.07), (1, 0, 0), (-160, 160), 320),
        ("j5", (0.302, 0, 0), (0, 1, 0), (-120, 120), 320),
        ("j6", (0.072, 0, 0), (1, 0, 0), (-400, 400), 420),
    ]
    src = "ROS-Industrial abb_irb120_support irb120_3_58 (ABB IRB 120 product specification)"
    return _arm("abb_irb120", rows, TOOL0, [0, 0, 0, 0, 90, 0], src)


def abb_irb140() -> Robot:
    """ABB IRB 140 (6 kg, 0.81 m), from ABB's IRB 140 product specification: axis 2 at
    0.352 m and 0.070 m ahead of axis 1, upper arm 0.360, axis 3 to the wrist centre
    0.380, wrist centre to flange 0.065 m; limits +-180, -90..110, -230..50, +-200,
    +-115, +-400 deg; speeds 200, 200, 260, 360, 360, 450 deg/s; reach 810 mm."""
    rows: list[Row] = [
        ("j1", (0, 0, 0), (0, 0, 1), (-180, 180), 200),
        ("j2", (0.070, 0, 0.352), (0, 1, 0), (-90, 110), 200),
        ("j3", (0, 0, 0.360), (0, 1, 0), (-230, 50), 260),
        ("j4", (0, 0, 0), (1, 0, 0), (-200, 200), 360),
        ("j5", (0.380, 0, 0), (0, 1, 0), (-115, 115), 360),
        ("j6", (0.065, 0, 0), (1, 0, 0), (-400, 400), 450),
    ]
    src = "ABB IRB 140 product specification (dimensions, axis working ranges, axis speeds)"
    return _arm("abb_irb140", rows, TOOL0, [0, 0, 0, 0, 90, 0], src)


def abb_irb2400() -> Robot:
    """ABB IRB 2400/10: the ROS-Industrial ``abb_irb2400_support`` description (axis 2 at
    0.615 m and 0.100 m ahead, upper arm 0.705, forearm 0.755 with a 0.135 m rise, flange
    0.085 m: the published OPW set a1 0.100, a2 -0.135, c1 0.615, c2 0.705, c3 0.755, c4
    0.085, offset3 -90 deg); limits +-180, -100..110, -60..65, +-200, +-120, +-400 deg;
    speeds 150, 150, 150, 360, 360, 450 deg/s; reach 1550 mm."""
    rows: list[Row] = [
        ("j1", (0, 0, 0), (0, 0, 1), (-180, 180), 150),
        ("j2", (0.100, 0, 0.615), (0, 1, 0), (-100, 110), 150),
        ("j3", (0, 0, 0.705), (0, 1, 0), (-60, 65), 150),
        ("j4", (0.258, 0, 0.135), (1, 0, 0), (-200, 200), 360),
        ("j5", (0.497, 0, 0), (0, 1, 0), (-120, 120), 360),
        ("j6", (0.085, 0, 0), (1, 0, 0), (-400, 400), 450),
    ]
    src = "ROS-Industrial abb_irb2400_support (ABB IRB 2400 product specification); OPW set of opw_kinematics"
    return _arm("abb_irb2400", rows, TOOL0, [0, 0, 0, 0, 90, 0], src)


# ---------------------------------------------------------------------------- FANUC
def fanuc_lrmate200id() -> Robot:
    """FANUC LR Mate 200iD: the ROS-Industrial ``fanuc_lrmate200id_support`` description
    (J1 at 0.330 m, J2 0.050 ahead, upper arm 0.330, forearm 0.335 with a 0.035 m rise,
    flange 0.080; J3, J4, J5, J6 turn about -y, -x, -y, -x; limits +-170, -100..145,
    -140..280, +-190, +-125, +-360 deg; speeds 450, 380, 520, 550, 545, 1000 deg/s);
    reach 717 mm. Joint 3 is the URDF's (relative to the upper arm); FANUC's controller
    reports J3 from the horizontal (J3_fanuc = J3 - J2, the ROS-I driver's J23_factor 1)."""
    rows: list[Row] = [
        ("j1", (0, 0, 0.330), (0, 0, 1), (-169.88, 169.88), 450),
        ("j2", (0.050, 0, 0), (0, 1, 0), (-100, 145), 380),
        ("j3", (0, 0, 0.330), (0, -1, 0), (-140.43, 280), 520),
        ("j4", (0, 0, 0.035), (-1, 0, 0), (-189.94, 189.94), 550),
        ("j5", (0.335, 0, 0), (0, -1, 0), (-124.9, 124.9), 545),
        ("j6", (0.080, 0, 0), (-1, 0, 0), (-360.1, 360.1), 1000),
    ]
    tool = spatial.euler((np.pi, -np.pi / 2, 0.0))
    src = "ROS-Industrial fanuc_lrmate200id_support (FANUC LR Mate 200iD data sheet limits and speeds)"
    return _arm("fanuc_lrmate200id", rows, tool, [0, 0, 0, 0, -90, 0], src)
