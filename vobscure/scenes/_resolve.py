"""The one place where a scene argument becomes a :class:`Scene`: a Scene, a
``trimesh.Trimesh``, a built-in scene's name (:func:`names`) or a mesh file's path."""

from __future__ import annotations

import os
from pathlib import Path

import trimesh

from ._scene import Scene
from .io import SUPPORTED_EXTENSIONS, load
from .procedural import get, names

__all__ = ["as_scene", "check_spec", "resolve"]

#: The name :func:`resolve` gives a scene that is neither built in nor read from a file.
CUSTOM = "custom"


def _accepted() -> str:
    return (f"a vobscure Scene, a trimesh.Trimesh, a built-in scene name ({', '.join(names())}) "
            f"or the path of a mesh file ({', '.join(SUPPORTED_EXTENSIONS)})")


def resolve(spec, *, argument: str = "scene") -> tuple[Scene, str]:
    """The scene that ``spec`` names, and its name.

    Parameters
    ----------
    spec : Scene, trimesh.Trimesh, str or os.PathLike
        A :class:`Scene` (returned as is), a ``trimesh.Trimesh`` (wrapped in a Scene), the
        name of a built-in scene (:func:`vobscure.scenes.names`, built with its default
        arguments by :func:`vobscure.scenes.get`), or the path of a mesh file
        (:func:`vobscure.scenes.load`). A string that is a built-in name is that scene even
        when a file of that name exists; write ``"./slab"`` for the file.
    argument : str, optional
        The argument's name in error messages (default ``"scene"``).

    Returns
    -------
    scene : Scene
    name : str
        The built-in name, the file's stem, or ``"custom"`` for a Scene or Trimesh given
        directly.

    Raises
    ------
    ValueError
        For any other type, or a string that is neither a built-in name nor a path (the
        message lists the built-in names).
    FileNotFoundError
        For a path (a string with a file extension, or an existing path) that does not
        exist; the message also lists the built-in names.

    Examples
    --------
    >>> from vobscure.scenes import resolve
    >>> scene, name = resolve("crease")
    >>> name, scene.name
    ('crease', 'crease')
    >>> resolve(scene)[1]
    'custom'
    """
    if isinstance(spec, Scene):
        return spec, CUSTOM
    if isinstance(spec, trimesh.Trimesh):
        return Scene(spec), CUSTOM
    spec = check_spec(spec, argument=argument)
    if spec in names():
        return get(spec), spec
    path = Path(spec).expanduser()
    return load(path), path.stem


def check_spec(spec, *, argument: str = "scene", exists: bool = True) -> str:
    """A built-in scene's name or a mesh file's path, checked without building or loading it
    (for scenes that other processes will resolve).

    Parameters
    ----------
    spec : str or os.PathLike
    argument : str, optional
        The argument's name in error messages.
    exists : bool, optional
        Require the file to exist here (default). False only checks that the path names a
        supported mesh format: for a path that other machines (a cluster's workers) will read.

    Returns
    -------
    str
        ``spec`` as a string (a path-like is converted).

    Raises
    ------
    ValueError, FileNotFoundError
        As :func:`resolve`.

    Examples
    --------
    >>> check_spec("cornell_box")
    'cornell_box'
    >>> check_spec("/data/on/the/workers/bunny.ply", exists=False)
    '/data/on/the/workers/bunny.ply'
    """
    if isinstance(spec, os.PathLike):
        spec = os.fspath(spec)
    if not isinstance(spec, str):
        raise ValueError(f"{argument} must be {_accepted()}; got {type(spec).__name__}")
    if spec in names():
        return spec
    path = Path(spec).expanduser()
    if not exists:
        if path.suffix.lower() in SUPPORTED_EXTENSIONS:
            return spec
        raise ValueError(f"{argument} must be a built-in scene ({', '.join(names())}) or a mesh file "
                         f"({', '.join(SUPPORTED_EXTENSIONS)}); got {spec!r}")
    if path.suffix or path.exists():
        if not path.exists():
            raise FileNotFoundError(f"{argument} {spec!r} is not a built-in scene ({', '.join(names())}) "
                                    f"and no such mesh file exists")
        return spec
    raise ValueError(f"{argument} must be {_accepted()}; got {spec!r}, which is neither a built-in "
                     f"name nor a path")


def as_scene(scene, *, argument: str = "scene") -> Scene:
    """``scene`` as a :class:`Scene`: :func:`resolve` without the name.

    Every function of vobscure that takes a scene accepts what this accepts.

    Examples
    --------
    >>> import trimesh
    >>> from vobscure.scenes import Scene, as_scene
    >>> as_scene("slab").name
    'slab'
    >>> isinstance(as_scene(trimesh.creation.box()), Scene)
    True
    """
    return resolve(scene, argument=argument)[0]
