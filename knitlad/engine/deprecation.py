"""Renamed public names keep working for at least one version, with a DeprecationWarning (CHANGELOG.md)."""

from __future__ import annotations

import dataclasses
import functools
import sys
import warnings


def _called_by_replace(depth: int = 16) -> bool:
    """Whether ``dataclasses.replace`` is among the callers (through the stacked renaming wrappers)."""
    frame = sys._getframe(2)
    for _ in range(depth):
        if frame is None:
            return False
        if frame.f_code is dataclasses.replace.__code__:
            return True
        frame = frame.f_back
    return False


def renamed_field(old: str, new: str, since: str):
    """Class decorator: the constructor keyword and the attribute ``old`` of a dataclass still work, as
    ``new`` (renamed in version ``since``), and say so once per call site."""

    def decorate(cls):
        init = cls.__init__

        @functools.wraps(init)
        def __init__(self, *args, **kwargs):
            if old in kwargs:
                warnings.warn(f"{cls.__name__}({old}=...) is deprecated since {since}: use {new}=",
                              DeprecationWarning, stacklevel=2)
                # dataclasses.replace(obj, old=...) passes every field under its new name too: the change wins
                if new in kwargs and not _called_by_replace():
                    raise TypeError(f"{cls.__name__}: give {new}, not both {new} and {old}")
                kwargs[new] = kwargs.pop(old)
            init(self, *args, **kwargs)

        def getter(self):
            warnings.warn(f"{cls.__name__}.{old} is deprecated since {since}: use .{new}", DeprecationWarning,
                          stacklevel=2)
            return getattr(self, new)

        cls.__init__ = __init__
        setattr(cls, old, property(getter, doc=f"Deprecated since {since}: :attr:`{new}`."))
        return cls

    return decorate


def renamed_fields(renames: dict[str, str], since: str):
    """Class decorator: :func:`renamed_field` for each ``old: new`` of ``renames``."""

    def decorate(cls):
        for old, new in renames.items():
            cls = renamed_field(old, new, since)(cls)
        return cls

    return decorate


def renamed_arguments(renames: dict[str, str], since: str):
    """Function decorator: the keyword arguments ``old`` of ``renames`` still work as ``new`` (renamed in version
    ``since``), with a DeprecationWarning; both at once is a TypeError."""

    def decorate(function):
        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            for old, new in renames.items():
                if old in kwargs:
                    warnings.warn(f"{function.__name__}({old}=...) is deprecated since {since}: use {new}=",
                                  DeprecationWarning, stacklevel=2)
                    if new in kwargs:
                        raise TypeError(f"{function.__name__}: give {new}, not both {new} and {old}")
                    kwargs[new] = kwargs.pop(old)
            return function(*args, **kwargs)

        return wrapper

    return decorate


def removed_argument(kwargs: dict, owner: str, name: str, default, since: str, why: str) -> None:
    """Take ``name`` out of ``kwargs``: an argument of ``owner`` removed in version ``since``. At its old default it
    changed nothing, and still works for a version with a DeprecationWarning; any other value is refused
    (ValueError, saying ``why``)."""
    if name not in kwargs:
        return
    value = kwargs.pop(name)
    if value != default:
        raise ValueError(f"{name} was removed in {since} ({why}); only its old default {default!r} is still accepted")
    warnings.warn(f"{owner}({name}=...) is deprecated since {since} and changes nothing: {why}", DeprecationWarning,
                  stacklevel=3)


def removed_field(name: str, default, since: str, why: str):
    """Class decorator: the constructor keyword ``name`` of a dataclass, removed in version ``since``
    (:func:`removed_argument`)."""

    def decorate(cls):
        init = cls.__init__

        @functools.wraps(init)
        def __init__(self, *args, **kwargs):
            removed_argument(kwargs, cls.__name__, name, default, since, why)
            init(self, *args, **kwargs)

        cls.__init__ = __init__
        return cls

    return decorate
