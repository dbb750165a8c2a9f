"""The ParaView file of a run: ``write_xdmf`` puts ``<name>.xdmf`` beside an HDF5 run or trajectory file,
through which ParaView opens the frames as line cells with per-node fields over time (course, velocity,
axial strain, curvature, contact state) and, for a trajectory of one's own scene, its touching pairs as
points with their forces. The XDMF only points into the HDF5 file (hyperslabs): nothing is copied."""

from __future__ import annotations

from pathlib import Path

import h5py

from knitlad.io.atomic import atomic_path


def _hyperslab(ref: str, start: tuple, count: tuple, full: tuple, dims: tuple, number_type: str = "Float",
               precision: int = 4) -> str:
    """An XDMF DataItem selecting the block ``count`` at ``start`` of the HDF5 dataset ``ref``
    ("file.h5:/path", shape ``full``), read as an array of shape ``dims``."""
    dims = " ".join(map(str, dims))
    selection = " ".join(map(str, (*start, *(1 for _ in start), *count)))
    return (f'<DataItem ItemType="HyperSlab" Dimensions="{dims}" Type="HyperSlab">'
            f'<DataItem Dimensions="3 {len(start)}" Format="XML">{selection}</DataItem>'
            f'<DataItem Dimensions="{" ".join(map(str, full))}" NumberType="{number_type}" Precision="{precision}" '
            f'Format="HDF">{ref}</DataItem></DataItem>')


def _contact_points_xdmf(h5: Path) -> str:
    """A second temporal collection, "contacts": each frame's touching pairs as points with their normal and
    friction forces [N] and sliding flag (``/contacts`` of a trajectory file; "" if it has none). A frame
    without a touching pair shows one point at the origin with zero force (XDMF has no empty grid)."""
    with h5py.File(h5, "r") as f:
        if "contacts" not in f:
            return ""
        offsets = f["contacts/offsets"][()]
        times = f["frames/time"][()]
    total = int(offsets[-1])
    if total == 0:
        return ""
    zero = '<DataItem Dimensions="1 3" Format="XML">0 0 0</DataItem>'
    grids = []
    for k, t in enumerate(times):
        start, count = int(offsets[k]), int(offsets[k + 1] - offsets[k])

        def rows(path: str, cols: int = 3) -> str:  # frame k's rows of a concatenated dataset
            if count == 0:  # nothing touches: one point at the origin, zero force
                return zero if cols == 3 else '<DataItem Dimensions="1" Format="XML">0</DataItem>'
            if cols == 1:
                return _hyperslab(f"{h5.name}:{path}", (start,), (count,), (total,), (count,), "UChar", 1)
            return _hyperslab(f"{h5.name}:{path}", (start, 0), (count, cols), (total, cols), (count, cols))

        grids.append(f'<Grid Name="c{k}" GridType="Uniform"><Time Value="{t:.9g}"/>'
                     f'<Topology TopologyType="Polyvertex" NumberOfElements="{max(count, 1)}" NodesPerElement="1"/>'
                     f'<Geometry GeometryType="XYZ">{rows("/contacts/points")}</Geometry>'
                     f'<Attribute Name="normal_force" Center="Node" AttributeType="Vector">'
                     f'{rows("/contacts/normal_force")}</Attribute>'
                     f'<Attribute Name="friction_force" Center="Node" AttributeType="Vector">'
                     f'{rows("/contacts/friction_force")}</Attribute>'
                     f'<Attribute Name="sliding" Center="Node" AttributeType="Scalar">{rows("/contacts/sliding", 1)}'
                     '</Attribute></Grid>')
    return '<Grid Name="contacts" GridType="Collection" CollectionType="Temporal">' + "".join(grids) + "</Grid>"


def write_xdmf(h5: str | Path) -> Path:
    """``ladder.xdmf`` beside ``h5``: a temporal collection of line meshes over the frames, with
    per-node course, velocity [m/s], axial strain, curvature [1/m] (``/fields`` of ``h5``) and contact
    state (0 free, 1 touching, 2 sliding); for a trajectory of one's own scene, named "yarns", and its
    touching pairs as a second collection, "contacts"."""
    from knitlad.io.kinds import is_trajectory

    h5 = Path(h5)
    with h5py.File(h5, "r") as f:
        if "fields" not in f:
            raise ValueError(f"{h5}: no per-node fields (written by an older knitlad)")
        n_frames, n = f["frames/positions"].shape[:2]
        edges = f["topology/edges"][()]
        times = f["frames/time"][()]
        has_contact = "contact" in f["frames"]
        grid_name = "yarns" if is_trajectory(f) else "ladder"
    name = h5.name
    steps = []

    def contact(k: int) -> str:
        if not has_contact:
            return ""
        return (f'<Attribute Name="contact (0 free, 1 touching, 2 sliding)" Center="Node" AttributeType="Scalar">'
                f'{_hyperslab(f"{name}:/frames/contact", (k, 0), (1, n), (n_frames, n), (n,), "UChar", 1)}</Attribute>')

    for k, t in enumerate(times):
        def item(path, cols):  # frame k of an (n_frames, n[, cols]) dataset
            if cols == 1:
                return _hyperslab(f"{name}:{path}", (k, 0), (1, n), (n_frames, n), (n,))
            return _hyperslab(f"{name}:{path}", (k, 0, 0), (1, n, cols), (n_frames, n, cols), (n, cols))

        steps.append(
            f'<Grid Name="t{k}" GridType="Uniform"><Time Value="{t:.9g}"/>'
            f'<Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{len(edges)}">'
            # the whole edge list as a slab of itself: VTK's reader caches a grid whose topology is a plain
            # DataItem by the text of its geometry's, which a slab has not ("ERR| Cannot find DataItem element
            # in geometry xml" at every read); a slab topology turns that cache off, as every frame moves anyway
            f'{_hyperslab(f"{name}:/topology/edges", (0, 0), (len(edges), 2), (len(edges), 2), (len(edges), 2), "Int", 8)}'
            f'</Topology>'
            f'<Geometry GeometryType="XYZ">{item("/frames/positions", 3)}</Geometry>'
            f'<Attribute Name="course" Center="Node" AttributeType="Scalar"><DataItem Dimensions="{n}" '
            f'NumberType="Int" Precision="8" Format="HDF">{name}:/topology/node_course</DataItem></Attribute>'
            f'<Attribute Name="velocity" Center="Node" AttributeType="Vector">{item("/frames/velocities", 3)}</Attribute>'
            f'<Attribute Name="axial_strain" Center="Node" AttributeType="Scalar">{item("/fields/axial_strain", 1)}'
            f'</Attribute>'
            f'<Attribute Name="curvature" Center="Node" AttributeType="Scalar">{item("/fields/curvature", 1)}'
            f'</Attribute>{contact(k)}</Grid>')
    text = (f'<?xml version="1.0" ?>\n<Xdmf Version="2.0"><Domain><Grid Name="{grid_name}" GridType="Collection" '
            'CollectionType="Temporal">' + "".join(steps) + "</Grid>" + _contact_points_xdmf(h5) +
            "</Domain></Xdmf>\n")
    xdmf = h5.with_suffix(".xdmf")
    with atomic_path(xdmf) as tmp:
        tmp.write_text(text)
    return xdmf


