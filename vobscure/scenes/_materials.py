"""The alpha of materials in mesh files: what :func:`vobscure.scenes.load` reads for alpha testing.

OBJ / MTL (Alias|Wavefront, *File Formats* v4.2, 1995, ch. 5 "Material Library File"):

- ``d`` is the dissolve (1 opaque); ``Tr`` is not in the specification, and is read as
  ``1 - d`` when ``d`` is absent (the common convention; some exporters write ``Tr`` as the
  opacity instead, so a ``Tr`` that makes a material a hole is warned about).
- ``map_d`` is "a scalar texture ... linked to the dissolve ... the map_d value is multiplied
  by the d value"; the channel is ``-imfchan`` (r, g, b, m = matte/alpha, l = luminance),
  whose default for scalar textures is luminance. An image with an alpha channel is read
  through that channel instead, as Blender's OBJ importer does (it links the map_d image's
  Alpha output to the shader's Alpha; ``importer/obj_import_mtl.cc``); its exporter writes
  the image linked to the shader's Alpha input as map_d (``exporter/obj_export_mtl.cc``),
  typically the RGBA colour image whose alpha is the cut-out.
- The alpha channel of ``map_Kd``, when its image has one and there is no ``map_d``, is read
  as the dissolve too (said in a warning: the specification has no such rule).
- MTL has no cutoff: :data:`MTL_CUTOFF`.

glTF 2.0: ``material.alphaMode`` ``MASK`` with ``alphaCutoff`` (default 0.5; "if the alpha
value is greater than or equal to this value then it is rendered as fully opaque, otherwise
... fully transparent"); the alpha is ``pbrMetallicRoughness.baseColorFactor[3]`` times the
alpha of ``baseColorTexture`` ("if a baseColorTexture is specified, this value is multiplied
with the texel values"). ``BLEND`` is read as a mask at 0.5 (said in a warning); ``OPAQUE``
has no alpha. trimesh reads ``TEXCOORD_0`` with v flipped to point up
(``trimesh/exchange/gltf/__init__.py``: ``uv[:, 1] = 1.0 - uv[:, 1]``), the convention of
:class:`AlphaMask`.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["AlphaWarning", "MTL_CUTOFF", "MaterialAlpha", "mtl_libraries", "mtl_materials", "gltf_materials",
           "gltf_material", "match_gltf_material", "image_channel"]

#: Cutoff of MTL materials (MTL has none): 0.5, glTF's default ``alphaCutoff``.
MTL_CUTOFF = 0.5

#: MTL texture options that do not change which texels are read (blending, mip-map
#: sharpness, bump multiplier, colour correction, resolution): accepted and ignored.
_HARMLESS = {"-blendu": 1, "-blendv": 1, "-boost": 1, "-bm": 1, "-cc": 1, "-texres": 1, "-type": 1}
#: Options whose identity values are harmless, and that cannot be honoured otherwise.
_TRANSFORMS = {"-o": (0.0, 0.0, 0.0), "-s": (1.0, 1.0, 1.0), "-t": (0.0, 0.0, 0.0), "-mm": (0.0, 1.0)}


class AlphaWarning(UserWarning):
    """Emitted by :func:`vobscure.scenes.load` about the alpha of materials: a part of a
    material that cannot be honoured (the mesh is then loaded solid), a reading that goes
    beyond the format's specification, or ``alpha=False``. The message names the file, the
    material and the meshes."""


@dataclass
class MaterialAlpha:
    """The alpha of one material: ``factor`` times ``texture`` (None: a constant), cut at
    ``cutoff``. ``problem`` says why it cannot be honoured (the faces are then solid)."""

    name: str
    factor: float = 1.0
    texture: np.ndarray | None = None
    cutoff: float = MTL_CUTOFF
    problem: str | None = None
    notes: list = field(default_factory=list)

    @property
    def alpha(self) -> np.ndarray:
        """(h, w) float32 alpha: the texture times the factor, or the factor as a 1 x 1 texture."""
        if self.texture is None:
            return np.full((1, 1), self.factor, dtype=np.float32)
        return np.clip(self.texture * np.float32(self.factor), 0.0, 1.0).astype(np.float32)

    @property
    def is_masked(self) -> bool:
        """Whether any texel is a hole (otherwise the material is opaque)."""
        return bool(np.any(self.alpha.astype(np.float64) < self.cutoff))


def image_channel(image, channel: str | None = None) -> np.ndarray:
    """(h, w) float32 in [0, 1]: one channel of a PIL image, row 0 the top.

    ``channel``: ``"r"``, ``"g"``, ``"b"``, ``"m"`` (matte: the alpha channel, 1 where the
    image has none), ``"l"`` (luminance, Pillow's ITU-R 601-2 ``L``), or None: the alpha
    channel when the image has one, else the luminance.
    """
    mode = image.mode
    has_alpha = mode in ("RGBA", "LA", "PA", "RGBa", "La") or "transparency" in image.info
    if channel is None:
        channel = "m" if has_alpha else "l"
    if mode.startswith("I") or mode == "F":           # 16- or 32-bit single channel
        values = np.asarray(image, dtype=np.float64)
        top = 1.0 if mode == "F" else 65535.0
        grey = np.clip(values / top, 0.0, 1.0).astype(np.float32)
        return np.ones_like(grey) if channel == "m" else grey
    if channel == "m":
        if not has_alpha:
            return np.ones((image.height, image.width), dtype=np.float32)
        return np.asarray(image.convert("RGBA"), dtype=np.float32)[..., 3] / 255.0
    if channel == "l":
        return np.asarray(image.convert("L"), dtype=np.float32) / 255.0
    return np.asarray(image.convert("RGB"), dtype=np.float32)[..., "rgb".index(channel)] / 255.0


def has_alpha_channel(image) -> bool:
    return image.mode in ("RGBA", "LA", "PA", "RGBa", "La") or "transparency" in image.info


def _open_image(path: Path):
    from PIL import Image

    image = Image.open(path)
    image.load()
    return image


# -- OBJ / MTL -----------------------------------------------------------------------------
def mtl_libraries(obj_path: Path) -> list[Path]:
    """The MTL files an OBJ file names (``mtllib``), relative to its folder."""
    out = []
    with open(obj_path, "r", errors="replace") as f:
        for line in f:
            if line.startswith("mtllib"):
                rest = line[6:].strip()
                if not rest:
                    continue
                candidate = obj_path.parent / rest
                names = [rest] if candidate.exists() else rest.split()
                out.extend(obj_path.parent / n for n in names)
    return out


def _map_statement(tokens: list[str]):
    """(options dict, file name) of a ``map_*`` statement's arguments."""
    options, i = {}, 0
    while i < len(tokens) - 1 and tokens[i].startswith("-"):
        key = tokens[i].lower()
        if key in ("-o", "-s", "-t"):
            args = []
            i += 1
            while i < len(tokens) - 1 and len(args) < 3 and _is_float(tokens[i]):
                args.append(float(tokens[i]))
                i += 1
            options[key] = args
            continue
        count = 2 if key == "-mm" else _HARMLESS.get(key, 1)
        options[key] = tokens[i + 1:i + 1 + count]
        i += 1 + count
    return options, " ".join(tokens[i:])


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _texture_problem(options: dict) -> str | None:
    """Why the options of a map statement cannot be honoured, or None."""
    for key, value in options.items():
        if key in _HARMLESS or key == "-imfchan":
            continue
        if key == "-clamp":
            if [v.lower() for v in value] != ["off"]:
                return "texture option -clamp on (the alpha test repeats texture coordinates)"
            continue
        if key in _TRANSFORMS:
            identity = _TRANSFORMS[key]
            try:
                numbers = [float(v) for v in value]
            except ValueError:
                return f"texture option {key} {' '.join(map(str, value))} cannot be read"
            if any(abs(v - identity[k]) > 0 for k, v in enumerate(numbers)):
                return f"texture option {key} {' '.join(map(str, value))} (texture transforms are not applied)"
            continue
        return f"texture option {key} is not supported"
    channel = options.get("-imfchan", ["l"])
    if channel and channel[0].lower() not in ("r", "g", "b", "m", "l"):
        return f"texture option -imfchan {channel[0]} (only r, g, b, m, l are read)"
    return None


def mtl_materials(obj_path: Path, *, read_images: bool = True) -> dict[str, MaterialAlpha]:
    """The materials of an OBJ file's MTL libraries that have an alpha (d or Tr below 1,
    ``map_d``, or a ``map_Kd`` image with an alpha channel), by name.

    With ``read_images=False`` no image is opened (``map_Kd`` is then not looked at), for
    telling whether a file has alpha at all.
    """
    out: dict[str, MaterialAlpha] = {}
    for library in mtl_libraries(obj_path):
        if not library.exists():
            continue        # trimesh loads the geometry without it; nothing has alpha
        statements: dict[str, dict] = {}
        current = None
        with open(library, "r", errors="replace") as f:
            for raw in f:
                tokens = raw.strip().split()
                if not tokens or tokens[0].startswith("#"):
                    continue
                key = tokens[0].lower()
                if key == "newmtl":
                    current = " ".join(tokens[1:])
                    statements[current] = {}
                elif current is not None and key in ("d", "tr", "map_d", "map_kd") and len(tokens) > 1:
                    statements[current][key] = tokens[1:]
        for name, st in statements.items():
            material = _mtl_material(name, st, library.parent, read_images)
            if material is not None:
                out[name] = material
    return out


def _mtl_material(name: str, st: dict, folder: Path, read_images: bool) -> MaterialAlpha | None:
    m = MaterialAlpha(name)
    d = tr = None
    try:
        if "d" in st:
            # "d -halo factor" makes the dissolve depend on the view: not an alpha test
            if st["d"][0].lower() == "-halo":
                m.problem = "dissolve with -halo (depends on the view)"
                return m
            d = float(st["d"][0])
        if "tr" in st:
            tr = float(st["tr"][0])
    except ValueError:
        m.problem = "a d or Tr value that is not a number"
        return m
    if d is not None:
        m.factor = d
        if tr is not None and abs((1.0 - tr) - d) > 1e-6:
            m.notes.append(f"d {d:g} and Tr {tr:g} disagree; d is used")
    elif tr is not None:
        m.factor = 1.0 - tr
        if m.factor < MTL_CUTOFF:
            m.notes.append(f"Tr {tr:g} is read as dissolve 1 - Tr = {m.factor:g}, which makes the material a hole "
                           "(some exporters write Tr as the opacity: check the file)")
    if not 0.0 <= m.factor <= 1.0:
        m.problem = f"dissolve {m.factor:g} outside [0, 1]"
        return m
    if 0.0 < m.factor < 1.0:
        m.notes.append(f"dissolve {m.factor:g} (partial transparency) is read as a mask at {MTL_CUTOFF}")
    source = None
    if "map_d" in st:
        options, filename = _map_statement(st["map_d"])
        source = ("map_d", options, filename)
    elif "map_kd" in st and read_images:
        options, filename = _map_statement(st["map_kd"])
        source = ("map_Kd", options, filename)
    elif "map_kd" in st:
        source = None
    if source is None:
        return m if m.factor < 1.0 or m.notes else None
    which, options, filename = source
    if not read_images:
        return m
    path = folder / filename.replace("\\", "/")
    if which == "map_d":
        m.problem = _texture_problem(options)
        if m.problem is not None:
            return m
    if not path.is_file():
        if which == "map_Kd":
            return m if m.factor < 1.0 or m.notes else None   # a missing colour map: no alpha from it
        m.problem = f"map_d texture file {filename!r} not found (looked for {path})"
        return m
    try:
        image = _open_image(path)
    except Exception as exc:  # Pillow raises many types for unreadable images
        if which == "map_Kd":
            return m if m.factor < 1.0 or m.notes else None
        m.problem = f"map_d texture {filename!r} cannot be read ({type(exc).__name__}: {exc})"
        return m
    if which == "map_Kd":
        if not has_alpha_channel(image):
            return m if m.factor < 1.0 or m.notes else None
        alpha = image_channel(image, "m")
        if alpha.min() >= 1.0:
            return m if m.factor < 1.0 or m.notes else None
        problem = _texture_problem(options)
        if problem is not None:
            m.problem = problem
            return m
        m.notes.append(f"alpha read from the alpha channel of its map_Kd image {filename!r} (no map_d; "
                       "the MTL specification has no such rule)")
        m.texture = alpha
        return m
    channel = options.get("-imfchan", [None])[0]
    m.texture = image_channel(image, channel.lower() if channel else None)
    return m


# -- glTF ----------------------------------------------------------------------------------
def _gltf_json(path: Path) -> dict:
    """The JSON of a .gltf file or of a .glb file's first chunk."""
    data = path.read_bytes()
    if path.suffix.lower() == ".glb" or data[:4] == b"glTF":
        if len(data) < 20 or data[:4] != b"glTF":
            raise ValueError("not a binary glTF file")
        length, kind = struct.unpack_from("<II", data, 12)
        if kind != 0x4E4F534A:  # "JSON"
            raise ValueError("the first chunk of the binary glTF file is not JSON")
        data = data[20:20 + length]
    return json.loads(data.decode("utf-8"))


def gltf_materials(path: Path) -> list[dict]:
    """The alpha-relevant fields of each material of a glTF file, in the file's order:
    name, mode, cutoff, factor, texture (bool), texcoord, transform (bool), and ``meshes``:
    the names of the meshes whose primitives use it."""
    header = _gltf_json(path)
    out = []
    for i, mat in enumerate(header.get("materials", [])):
        pbr = mat.get("pbrMetallicRoughness", {})
        factor = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
        texture = pbr.get("baseColorTexture")
        out.append({
            "key": mat.get("name"),          # what trimesh's PBRMaterial.name holds (None unnamed)
            "name": mat.get("name", f"material {i}"),
            "mode": str(mat.get("alphaMode", "OPAQUE")).upper(),
            "cutoff": float(mat.get("alphaCutoff", 0.5)),
            "factor": float(factor[3]) if len(factor) == 4 else 1.0,
            "texture": texture is not None,
            "texcoord": int(texture.get("texCoord", 0)) if texture else 0,
            "transform": bool(texture and "KHR_texture_transform" in texture.get("extensions", {})),
            "meshes": [],
        })
    for j, mesh in enumerate(header.get("meshes", [])):
        for prim in mesh.get("primitives", []):
            k = prim.get("material")
            if k is not None and 0 <= k < len(out):
                label = mesh.get("name", f"mesh {j}")
                if label not in out[k]["meshes"]:
                    out[k]["meshes"].append(label)
    return out


def _alpha_fields(info: dict) -> tuple:
    return (info["mode"], info["cutoff"], info["factor"], info["texture"], info["texcoord"], info["transform"])


def match_gltf_material(infos: list[dict], pbr) -> dict | None:
    """The entry of :func:`gltf_materials` that trimesh's PBRMaterial ``pbr`` came from, as far
    as the alpha is concerned: trimesh keeps a material's name, not its index, so the entries
    of that name whose fields agree with ``pbr``'s are taken; None when they differ in their
    alpha fields (the material cannot be told apart)."""
    name = getattr(pbr, "name", None)
    mode = str(getattr(pbr, "alphaMode", None) or "OPAQUE").upper()
    cutoff = getattr(pbr, "alphaCutoff", None)
    factor = getattr(pbr, "baseColorFactor", None)       # trimesh: uint8 RGBA
    candidates = [m for m in infos if m["key"] == name and m["mode"] == mode
                  and (cutoff is None or abs(m["cutoff"] - float(cutoff)) < 1e-6)
                  and (factor is None or abs(m["factor"] - float(factor[3]) / 255.0) <= 0.5 / 255.0 + 1e-9)]
    if not candidates or len({_alpha_fields(m) for m in candidates}) != 1:
        return None
    return candidates[0]


def gltf_material(info: dict, pbr) -> MaterialAlpha | None:
    """The alpha of a glTF material (``info`` from :func:`gltf_materials`, ``pbr`` trimesh's
    PBRMaterial of the same material, which holds the decoded base colour texture)."""
    mode = info["mode"]
    if mode not in ("MASK", "BLEND"):
        return None
    m = MaterialAlpha(info["name"], factor=info["factor"], cutoff=info["cutoff"] if mode == "MASK" else 0.5)
    if not 0.0 <= m.cutoff <= 1.0:
        # glTF: "a value greater than 1.0 will render the entire material as fully transparent"
        m.cutoff = min(max(m.cutoff, 0.0), 1.0)
        m.factor = 0.0 if info["cutoff"] > 1.0 else m.factor
    if mode == "BLEND":
        m.notes.append("alphaMode BLEND is read as a mask at 0.5")
    if info["texcoord"] != 0:
        m.problem = f"baseColorTexture uses texture coordinate set {info['texcoord']} (only set 0 is read)"
        return m
    if info["transform"]:
        m.problem = "baseColorTexture has a KHR_texture_transform (not applied)"
        return m
    if info["texture"]:
        image = getattr(pbr, "baseColorTexture", None) if pbr is not None else None
        if image is None:
            m.problem = "its baseColorTexture could not be read"
            return m
        m.texture = image_channel(image, "m")
    return m
