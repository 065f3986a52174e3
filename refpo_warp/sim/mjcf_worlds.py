"""Build one Newton model holding ``num_worlds`` identical copies of an MJCF scene, ready for ``SolverMuJoCo``.

Each copy is its own Newton world (no cross-world contacts). MuJoCo-specific MJCF content (actuators, tendons,
solver options, ``ref``, ``frictionloss``) is kept through ``SolverMuJoCo``'s custom attributes, so the MuJoCo model
that the solver compiles matches the one the MuJoCo C library compiles from the same file.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

MUJOCO_DEFAULT_TIMESTEP = 0.002


def mjcf_timestep(mjcf_path: str | Path) -> float:
    """The ``<option timestep>`` of an MJCF file (MuJoCo's default 0.002 s when absent).

    Newton does not take the timestep from the file (``SolverMuJoCo.step`` receives ``dt``), so callers read it here.
    """
    root = _parse(mjcf_path)
    option = root.find("option")
    value = option.get("timestep") if option is not None else None
    try:
        return float(value) if value is not None else MUJOCO_DEFAULT_TIMESTEP
    except ValueError as err:
        raise ValueError(f"{mjcf_path}: <option timestep='{value}'> is not a number") from err


def build_mjcf_worlds(
    mjcf_path: str | Path,
    num_worlds: int,
    device: str,
    contact_gap: float = 0.0,
    edit_world=None,
    ground=None,
    **mjcf_options,
):
    """Import ``mjcf_path`` once and replicate it into ``num_worlds`` worlds of one finalized Newton model.

    Args:
        mjcf_path: MJCF file (the same file the MuJoCo C library can load with ``MjModel.from_xml_path``).
        num_worlds: Number of worlds (parallel environments).
        device: Warp device of the model (``"cpu"`` or ``"cuda:N"``).
        contact_gap: Gap given to geoms that author none. MJCF's default is 0; Newton's own default widens contact
            detection by 0.1 m, which only adds inactive contacts (and halves the speed of contact-rich models).
        edit_world: Called with the one-world ``ModelBuilder`` after the import, before replication (e.g. to check
            the layout or set joint target gains in code).
        ground: A ``ModelBuilder.ShapeConfig`` for a ground plane shared by all worlds; None for none.
        mjcf_options: Keyword arguments of ``ModelBuilder.add_mjcf`` (e.g. ``floating``).
    """
    import newton
    from newton.solvers import SolverMuJoCo

    path = Path(mjcf_path)
    _parse(path)  # clear error for a missing or malformed file before Newton's importer runs
    if num_worlds < 1:
        raise ValueError(f"num_worlds must be >= 1, got {num_worlds}")

    world = newton.ModelBuilder()
    SolverMuJoCo.register_custom_attributes(world)  # keeps MuJoCo actuators, tendons and options from the file
    world.default_shape_cfg.gap = contact_gap
    world.add_mjcf(str(path), **mjcf_options)
    if edit_world is not None:
        edit_world(world)

    scene = newton.ModelBuilder()
    SolverMuJoCo.register_custom_attributes(scene)
    scene.replicate(world, num_worlds)
    if ground is not None:
        scene.add_ground_plane(cfg=ground)
    return scene.finalize(device=device)


def _parse(mjcf_path: str | Path) -> ET.Element:
    path = Path(mjcf_path)
    if not path.is_file():
        raise FileNotFoundError(f"MJCF file not found: {path}")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as err:
        raise ValueError(f"{path}: not valid XML ({err})") from err
    if root.tag != "mujoco":
        raise ValueError(f"{path}: the root element is <{root.tag}>, expected <mujoco>")
    return root
