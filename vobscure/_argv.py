"""The ``vobscure`` command's arguments as written: negative numbers and comma-separated lists
that start with a minus sign, which argparse would take for options, marked as values
(:func:`vobscure.cli.main` parses ``numbers_as_written(joined_list_values(argv))``)."""

from __future__ import annotations

__all__ = ["LIST_OPTIONS", "NUMBER_OPTIONS", "joined_list_values", "numbers_as_written"]

#: Options whose one value is a comma-separated list, which may start with a minus sign
#: (``--camera -14,2,0,0,1,0``): argparse would take such a value for an option, so it is
#: passed on as ``--camera=-14,2,0,0,1,0``.
LIST_OPTIONS = ("--camera",)


def joined_list_values(argv: list[str]) -> list[str]:
    """``argv`` with each :data:`LIST_OPTIONS` option and a following value that starts with
    ``-`` and holds a comma joined as ``OPTION=VALUE``."""
    out = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in LIST_OPTIONS and i + 1 < len(argv) and argv[i + 1].startswith("-") and "," in argv[i + 1]:
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


#: Options followed by this many numbers, which may be negative as written (``--eye -14 2 0``,
#: ``--fov 4e1``): argparse takes a value that starts with a minus sign for an option unless it
#: is a plain negative number (``-14``, ``-.5``), so each number of these options is passed on
#: with a leading space (``float`` ignores it, argparse then reads it as a value).
NUMBER_OPTIONS = {"--eye": 3, "--target": 3, "--up": 3, "--fov": 1}


def numbers_as_written(argv: list[str]) -> list[str]:
    """``argv`` with the numbers after each :data:`NUMBER_OPTIONS` option marked as values."""
    out = list(argv)
    i = 0
    while i < len(out):
        count = NUMBER_OPTIONS.get(out[i], 0)
        i += 1
        while count and i < len(out):
            try:
                float(out[i])
            except ValueError:
                break
            if out[i].startswith("-"):
                out[i] = " " + out[i]
            i, count = i + 1, count - 1
    return out
