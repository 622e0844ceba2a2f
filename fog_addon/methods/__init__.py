"""The fog's methods, each one unit behind ``base.Method``; ``resolve`` gives the one a spec asks for.

Method Auto (the default) chooses per scene (``auto.py``).  Adding a method: subclass ``base.Method``,
add an instance to ``METHODS_BY_NAME`` and its name to ``precompute.core.spec.METHODS``.
"""
from . import auto
from .base import Method  # noqa: F401
from .compositor import Compositor
from .node_groups import NodeGroups, Osl

METHODS_BY_NAME = {m.name: m for m in (NodeGroups(), Osl(), Compositor())}


def get(name):
    """The method called ``name`` ("nodes", "osl", "compositor")."""
    try:
        return METHODS_BY_NAME[name]
    except KeyError:
        raise ValueError(f"unknown method {name!r}; use one of auto, {', '.join(METHODS_BY_NAME)}") from None


def resolve(scene, spec, lights, materials):
    """(method, reason) for ``spec`` on ``scene``: Auto's choice (``auto.choose``) or the user's, whose reason
    is None.  ``lights``: the lights taking part; ``materials``: the fogged materials."""
    if spec.method == "auto":
        name, reason = auto.choose(scene, spec, lights, materials, METHODS_BY_NAME)
        return METHODS_BY_NAME[name], reason
    return get(spec.method), None
