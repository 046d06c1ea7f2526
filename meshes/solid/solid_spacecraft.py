"""Geometry of the spacecraft-like pair: a despun BUS (stator) and a spinning ROTOR with three booms.

One global frame (metres), z up. The spin bearing is at the origin: the bus's
top face is z = 0 and the rotor's hub sits on it, so both bearing RBE2 nodes
are at (0, 0, 0) and the revolute axis z passes through them.

  bus    2.0 x 1.2 x 1.2 m solid block below z = 0 (not square, so the system
         changes with the spin angle) with a 2.0 m, 0.1 x 0.1 m 'scan arm' along -x
         from the -x face at mid-height. RBE2 'bearing' on the top-face patch under
         the hub; RBE2 'pointA' on the arm's end face, carrying a 20 kg
         platform (Galileo's scan platform sits on the despun section).
  rotor  0.6 x 0.6 x 0.4 m hub above z = 0 carrying three 0.1 x 0.1 m booms at
         mid-height: 4.0 m along +x, 3.0 m along -x, 3.5 m along +y (unequal, so
         the rotor's inertia and modes change with the spin angle). RBE2
         'bearing' on the whole hub bottom face; RBE2 'tip' on the +x boom's end
         face carrying a 10 kg tip mass (a magnetometer-like instrument).

Element sizes at refine = 1 (divided by refine): bus block 0.15 m, hub 0.1 m,
booms and arm 0.05 m cubes (2 x 2 elements in the section). Cubes, not longer
elements, along the booms: a fully integrated hex8 in bending stiffens by a
parasitic shear term ~ (element length / section depth)^2 (README.md).
Aluminium everywhere: E = 70 GPa, nu = 0.33, rho = 2700 kg/m^3.
"""
from solid_grid import Block, BodySpec, Rbe2Patch

ALUMINIUM = dict(E=70e9, nu=0.33, rho=2700.0)

BUS_HALF_X, BUS_HALF_Y, BUS_HEIGHT = 1.0, 0.6, 1.2
ARM_LENGTH, ARM_Z = 2.0, (-0.65, -0.55)
PLATFORM_MASS = 20.0
HUB_HALF_WIDTH, HUB_HEIGHT = 0.3, 0.4
BOOM_HALF_SECTION = 0.05
BOOM_Z = (0.15, 0.25)
BOOM_LENGTHS = {"boom_px": 4.0, "boom_mx": 3.0, "boom_py": 3.5}
TIP_MASS = 10.0


def bus_spec():
    wx, wy, h = BUS_HALF_X, BUS_HALF_Y, BUS_HEIGHT
    hub, s = HUB_HALF_WIDTH, BOOM_HALF_SECTION
    z0, z1 = ARM_Z
    end = -wx - ARM_LENGTH
    return BodySpec(
        name="bus",
        blocks=[Block("bus_box", (-wx, -wy, -h), (wx, wy, 0.0), (0.15, 0.15, 0.15)),
                Block("scan_arm", (end, -s, z0), (-wx, s, z1), (0.05, 0.05, 0.05))],
        patches=[
            Rbe2Patch("bearing", axis=2, plane=0.0, lo=(-hub, -hub, 0.0), hi=(hub, hub, 0.0)),
            Rbe2Patch("pointA", axis=0, plane=end, lo=(0.0, -s, z0), hi=(0.0, s, z1), point_mass=PLATFORM_MASS),
        ],
        points={"corner": (wx, -wy, -h)},
        **ALUMINIUM,
    )


def rotor_spec():
    a, s = HUB_HALF_WIDTH, BOOM_HALF_SECTION
    z0, z1 = BOOM_Z
    hub_h, along, across = 0.1, 0.05, 0.05
    px, mx, py = (BOOM_LENGTHS[k] for k in ("boom_px", "boom_mx", "boom_py"))
    return BodySpec(
        name="rotor",
        blocks=[
            Block("hub", (-a, -a, 0.0), (a, a, HUB_HEIGHT), (hub_h, hub_h, hub_h)),
            Block("boom_px", (a, -s, z0), (a + px, s, z1), (along, across, across)),
            Block("boom_mx", (-a - mx, -s, z0), (-a, s, z1), (along, across, across)),
            Block("boom_py", (-s, a, z0), (s, a + py, z1), (across, along, across)),
        ],
        patches=[
            Rbe2Patch("bearing", axis=2, plane=0.0, lo=(-a, -a, 0.0), hi=(a, a, 0.0)),
            Rbe2Patch("tip", axis=0, plane=a + px, lo=(0.0, -s, z0), hi=(0.0, s, z1), point_mass=TIP_MASS),
        ],
        **ALUMINIUM,
    )
