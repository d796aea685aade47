"""A differential-drive robot's wheel geometry from its URDF, read the way caravan-world reads
it (processes/world/src/robot.rs): the two continuous joints are the wheels, each child link's
<cylinder> collision radius is the wheel radius, and the joints' y offsets give the separation.
"""

import xml.etree.ElementTree as ET

from .identity import BadInput


def wheel_geometry(path):
    """(wheel radius, wheel separation) in metres of the URDF at ``path``."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise BadInput(f"robot description {path}: {e}") from None
    links = {link.get("name"): link for link in root.findall("link")}
    wheels = []
    for joint in root.findall("joint"):
        if joint.get("type") != "continuous":
            continue
        child = links.get(joint.find("child").get("link"))
        cylinder = None if child is None else child.find("collision/geometry/cylinder")
        if cylinder is None:
            raise BadInput(
                f"robot description {path}: wheel joint '{joint.get('name')}' needs a child "
                "link with a <cylinder> collision shape"
            )
        origin = joint.find("origin")
        xyz = [float(v) for v in (origin.get("xyz") if origin is not None else "0 0 0").split()]
        wheels.append((xyz[1], float(cylinder.get("radius"))))
    if len(wheels) != 2:
        raise BadInput(
            f"robot description {path}: expected exactly two continuous (wheel) joints, "
            f"found {len(wheels)}"
        )
    (y_right, radius), (y_left, _) = sorted(wheels)
    return radius, y_left - y_right
