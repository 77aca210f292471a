"""scanmesh: range grids of rotary laser scanners and their meshers, from Python.

The compiled extension ``scanmesh._scanmesh`` binds the C++ library (docs/python.md); this file
re-exports it and adds the few helpers that are plain Python.
"""

from ._scanmesh import *  # noqa: F401,F403
from ._scanmesh import Mesh, __version__  # noqa: F401

_MESH_ARRAYS = ("positions", "triangles", "normals", "colors", "face_labels", "texcoords",
                "face_texcoords")


def _mesh_replace(self, **arrays):
    """A new Mesh with the named arrays replaced (the others copied from this mesh)."""
    unknown = set(arrays) - set(_MESH_ARRAYS)
    if unknown:
        raise TypeError("Mesh has no array " + ", ".join(sorted(unknown)))
    args = {name: getattr(self, name) for name in _MESH_ARRAYS}
    args.update(arrays)
    return Mesh(args.pop("positions"), args.pop("triangles"), **args)


Mesh.replace = _mesh_replace
