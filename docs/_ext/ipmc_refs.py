"""Resolve the short and module-path cross-references the docstrings use.

The packages' docstrings write ``:class:`State``` or ``:func:`physmodel.calibration.calibrate```
(the object's home module) while the reference documents each public object once, under the
name users import it by (``physmodel.calibrate``).  For a Python reference Sphinx could not
resolve, this resolver tries, in order:

1. the object the target names when imported (``physmodel.calibration.calibrate``): if a
   documented name is the same Python object, link there;
2. a unique documented name ending in ``.<target>`` (``State`` → ``physmodel.params.State``).

Anything still unresolved, or ambiguous, stays a warning (an error under ``-W``).
"""

from __future__ import annotations

import importlib

from docutils import nodes
from sphinx.util import logging

logger = logging.getLogger(__name__)


def _import(name: str):
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except Exception:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _index(env):
    cache = getattr(env, "_ipmc_suffix_index", None)
    objects = env.get_domain("py").objects
    if cache is None or cache[0] != len(objects):
        by_last: dict[str, list[str]] = {}
        for full, entry in objects.items():
            if getattr(entry, "aliased", False):   # ``:canonical:`` aliases of documented objects
                continue
            by_last.setdefault(full.rsplit(".", 1)[-1], []).append(full)
        cache = (len(objects), by_last)
        env._ipmc_suffix_index = cache
    return objects, cache[1]


def resolve(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    if not target or target.startswith("_"):
        return None
    objects, by_last = _index(env)
    candidates = [n for n in by_last.get(target.rsplit(".", 1)[-1], []) if n == target or n.endswith("." + target)]
    chosen = None
    obj = _import(target) if "." in target else None
    if obj is not None:
        same = [n for n in by_last.get(target.rsplit(".", 1)[-1], []) if _import(n) is obj]
        if len(same) >= 1:
            # documented once; prefer the shortest (the package-level) name
            chosen = min(same, key=len)
    if chosen is None and len(candidates) == 1:
        chosen = candidates[0]
    if chosen is None:
        return None
    entry = objects[chosen]
    newnode = nodes.reference("", "", internal=True)
    try:
        newnode["refuri"] = app.builder.get_relative_uri(node["refdoc"], entry.docname) + "#" + entry.node_id
    except Exception:  # pragma: no cover - builders without URIs
        return None
    newnode["reftitle"] = chosen
    newnode.append(contnode)
    return newnode


def setup(app):
    app.connect("missing-reference", resolve)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
