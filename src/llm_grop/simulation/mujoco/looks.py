"""What tableware looks like in renders: the visual geoms of ``assets/looks.yaml``.

A look is drawn by geoms that never collide and weigh nothing (they sit in
:data:`GROUP_VISUAL`, which renders draw and the lidar's rays pass through), while the
object's collision geoms, from its style, move to :data:`GROUP_COLLISION`, which renders
leave out and the lidar sees. Round parts are triangle meshes built
here: a lathe turns a profile about the object's axis, an arc sweeps a tube. Lengths in
metres, angles in radians unless a name says degrees.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Literal

import mujoco
import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from llm_grop.datafile import load_yaml_model

#: Geom group of collision geoms hidden behind a look: renders leave it out, the lidar
#: sees it.
GROUP_COLLISION = 4
#: Geom group of what is drawn only (looks, placemats): renders draw it, the lidar's rays
#: pass through it.
GROUP_VISUAL = 1
#: Facets round the tube of an arc.
TUBE_FACETS = 12
#: Facets along an arc.
ARC_FACETS = 20

Pair = tuple[float, float]
Triple = tuple[float, float, float]


class _PartModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    type: Literal["lathe", "box", "ellipsoid", "arc"]
    profile: list[Pair] | None = Field(default=None, min_length=3)
    x: Pair | None = None
    y: Pair | None = None
    z: Pair | None = None
    at: tuple[float, ...] | None = None
    radii: Triple | None = None
    radius: float | None = Field(default=None, gt=0)
    tube: float | None = Field(default=None, gt=0)
    degrees: Pair | None = None

    @model_validator(mode="after")
    def _complete(self) -> _PartModel:
        need = {"lathe": ("profile",), "box": ("x", "y", "z"), "ellipsoid": ("at", "radii"),
                "arc": ("at", "radius", "tube", "degrees")}[self.type]
        missing = [k for k in need if getattr(self, k) is None]
        if missing:
            raise ValueError(f"a {self.type} needs {', '.join(missing)}")
        if self.at is not None and len(self.at) != (2 if self.type == "arc" else 3):
            raise ValueError(f"a {self.type}'s `at` has {2 if self.type == 'arc' else 3} "
                             "numbers")
        return self


class _FileModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    segments: int = Field(ge=8)
    looks: dict[str, list[_PartModel]]


@cache
def _file() -> _FileModel:
    text = resources.files("llm_grop.simulation.mujoco").joinpath(
        "assets/looks.yaml").read_text(encoding="utf-8")
    return load_yaml_model(text, "looks.yaml", _FileModel, "looks", "type")


def names() -> tuple[str, ...]:
    """The looks ``assets/looks.yaml`` defines."""
    return tuple(_file().looks)


@dataclass(frozen=True)
class Visual:
    """One visual geom of an object, in its body frame (metres): a primitive ``type`` of
    ``size`` at ``pos``, or a mesh (``vertices`` ``(N, 3)``, ``faces`` ``(M, 3)``)."""

    type: mujoco.mjtGeom
    pos: Triple = (0.0, 0.0, 0.0)
    size: Triple = (0.0, 0.0, 0.0)
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None


def visuals(look: str, size: Pair, height: float) -> tuple[Visual, ...]:
    """The visual geoms of ``look`` for an object of footprint ``size`` ``(sx, sy)`` and
    ``height`` (metres); ``KeyError`` for a look the file lacks."""
    f = _file()
    scale = np.array([size[0] / 2, size[1] / 2, height])
    out = []
    for p in f.looks[look]:
        if p.type == "box":
            lo = np.array([p.x[0], p.y[0], p.z[0]]) * scale  # type: ignore[index]
            hi = np.array([p.x[1], p.y[1], p.z[1]]) * scale  # type: ignore[index]
            out.append(Visual(mujoco.mjtGeom.mjGEOM_BOX, _triple((lo + hi) / 2),
                              _triple(np.abs(hi - lo) / 2)))
        elif p.type == "ellipsoid":
            out.append(Visual(mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                              _triple(np.array(p.at) * scale),
                              _triple(np.array(p.radii) * scale)))
        elif p.type == "lathe":
            v, t = lathe(p.profile, f.segments)  # type: ignore[arg-type]
            out.append(Visual(mujoco.mjtGeom.mjGEOM_MESH, vertices=v * scale, faces=t))
        else:
            assert p.at is not None and p.degrees is not None
            v, t = arc((p.at[0] * scale[0], p.at[1] * height), p.radius * height,
                       p.tube * height,  # type: ignore[operator]
                       (math.radians(p.degrees[0]), math.radians(p.degrees[1])))
            out.append(Visual(mujoco.mjtGeom.mjGEOM_MESH, vertices=v, faces=t))
    return tuple(out)


def lathe(profile: Sequence[Pair], segments: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed triangle mesh turning the closed outline ``profile`` (``(r, z)`` points)
    about the z axis in ``segments`` facets: vertices ``(N, 3)`` and faces ``(M, 3)``,
    wound so that their normals point out. A point on the axis (r = 0) is one vertex."""
    angles = 2 * math.pi * np.arange(segments) / segments
    ring: list[list[int]] = []
    vertices: list[Triple] = []
    for r, z in profile:
        if r <= 0:
            ring.append([len(vertices)] * segments)
            vertices.append((0.0, 0.0, z))
        else:
            ring.append(list(range(len(vertices), len(vertices) + segments)))
            vertices += [(r * math.cos(a), r * math.sin(a), z) for a in angles]
    faces = []
    n = len(profile)
    for i in range(n):
        a, b = ring[i], ring[(i + 1) % n]
        for k in range(segments):
            k1 = (k + 1) % segments
            for tri in ((a[k], a[k1], b[k1]), (a[k], b[k1], b[k])):
                if len(set(tri)) == 3:
                    faces.append(tri)
    v, f = np.array(vertices), np.array(faces, dtype=np.int32)
    if _signed_volume(v, f) < 0:
        f = f[:, ::-1].copy()
    return v, f


def arc(centre: Pair, radius: float, tube: float, span: Pair
        ) -> tuple[np.ndarray, np.ndarray]:
    """A tube of radius ``tube`` whose centre line is an arc of ``radius`` round
    ``centre`` ``(x, z)`` in the x-z plane, from angle ``span[0]`` to ``span[1]`` (0 = +x,
    pi/2 = +z); open at its ends, which a look buries in its body. Vertices and faces as
    :func:`lathe`'s, normals out."""
    cx, cz = centre
    vertices = []
    for i in range(ARC_FACETS + 1):
        u = span[0] + (span[1] - span[0]) * i / ARC_FACETS
        out = np.array([math.cos(u), 0.0, math.sin(u)])
        for j in range(TUBE_FACETS):
            w = 2 * math.pi * j / TUBE_FACETS
            d = math.cos(w) * out + math.sin(w) * np.array([0.0, 1.0, 0.0])
            vertices.append(np.array([cx, 0.0, cz]) + radius * out + tube * d)
    faces = []
    for i in range(ARC_FACETS):
        for j in range(TUBE_FACETS):
            a, b = i * TUBE_FACETS + j, i * TUBE_FACETS + (j + 1) % TUBE_FACETS
            c, d = a + TUBE_FACETS, b + TUBE_FACETS
            faces += [(a, c, d), (a, d, b)]
    v, f = np.array(vertices), np.array(faces, dtype=np.int32)
    # Normals out: away from the centre line at the first ring.
    n = np.cross(v[f[0, 1]] - v[f[0, 0]], v[f[0, 2]] - v[f[0, 0]])
    if float(n @ (v[f[0, 0]] - (np.array([cx, 0.0, cz]) + radius * np.array(
            [math.cos(span[0]), 0.0, math.sin(span[0])])))) < 0:
        f = f[:, ::-1].copy()
    return v, f


def _signed_volume(v: np.ndarray, f: np.ndarray) -> float:
    """The volume a closed mesh encloses, negative when its faces are wound inwards."""
    return float(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum()
                 / 6)


def _triple(a: np.ndarray) -> Triple:
    return (float(a[0]), float(a[1]), float(a[2]))


def add_look(spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, parts: Sequence[Visual],
             rgba: Sequence[float]) -> None:
    """Add ``parts`` to ``body`` (tableware ``name``) as visual geoms coloured ``rgba``:
    no contacts, no mass."""
    for k, p in enumerate(parts):
        kw: dict[str, object] = {}
        if p.type == mujoco.mjtGeom.mjGEOM_MESH:
            assert p.vertices is not None and p.faces is not None
            mesh = spec.add_mesh(name=f"{name}#look{k}")
            mesh.uservert = p.vertices.ravel().tolist()
            mesh.userface = p.faces.ravel().tolist()
            kw["meshname"] = mesh.name
        else:
            kw["size"], kw["pos"] = list(p.size), list(p.pos)
        body.add_geom(name=f"{name}#look{k}", type=p.type, rgba=list(rgba), contype=0,
                      conaffinity=0, group=GROUP_VISUAL, mass=0.0, **kw)
