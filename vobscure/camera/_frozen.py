"""The immutability, equality and hashing shared by the camera's value objects.

:class:`~vobscure.camera.Pose`, :class:`~vobscure.camera.Projection` and
:class:`~vobscure.camera.Camera` are immutable values: each sets its slots once, compares by
a key and hashes that key. :class:`Frozen` is their base; :func:`read_only` makes the
properties that expose their slots, and :func:`vector_repr` writes a vector in their reprs.
"""

from __future__ import annotations

import operator

__all__ = ["Frozen", "read_only", "vector_repr"]


class Frozen:
    """Base of an immutable value object with slots.

    A subclass sets its slots once, with :meth:`_set_slots`; afterwards setting or deleting
    any attribute raises AttributeError. The class that derives directly from ``Frozen`` starts
    a *family* (its subclasses belong to it): objects of one family compare equal when their
    :meth:`_key` tuples are equal, and comparing with an object of another family is
    ``NotImplemented``. The hash is the key's.

    Examples
    --------
    >>> class Point(Frozen):
    ...     __slots__ = ("_x",)
    ...     def __init__(self, x):
    ...         self._set_slots(_x=x)
    ...     def _key(self):
    ...         return (self._x,)
    >>> Point(1) == Point(1), len({Point(1), Point(1)}), Point(1) == (1,)
    (True, 1, False)
    >>> Point(1).y = 2
    Traceback (most recent call last):
    ...
    AttributeError: Point is immutable; cannot set 'y'
    """

    __slots__ = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if Frozen in cls.__bases__:
            cls._family = cls

    def _set_slots(self, **values) -> None:
        """Set the slots named by the keywords (the one way to write to the object)."""
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable; cannot set {name!r}")

    def __delattr__(self, name):
        raise AttributeError(f"{type(self).__name__} is immutable; cannot delete {name!r}")

    def _key(self) -> tuple:
        """The hashable tuple that identifies the object's value within its family."""
        raise NotImplementedError

    def __eq__(self, other):
        if not isinstance(other, self._family):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())


def read_only(*names: str) -> tuple[property, ...]:
    """One property per name, each returning the slot ``"_" + name`` (the attribute of that
    name documented by the class's docstring).

    Examples
    --------
    >>> class Size(Frozen):
    ...     __slots__ = ("_width", "_height")
    ...     width, height = read_only("width", "height")
    ...     def __init__(self):
    ...         self._set_slots(_width=4, _height=3)
    >>> Size().height
    3
    """
    return tuple(property(operator.attrgetter("_" + name), doc=f"``{name}`` (read-only).") for name in names)


def vector_repr(a) -> str:
    """A vector as a tuple of float reprs, ``"(1.0, 2.0)"``.

    Examples
    --------
    >>> vector_repr([1, 2.5])
    '(1.0, 2.5)'
    """
    return "(" + ", ".join(repr(float(x)) for x in a) + ")"
