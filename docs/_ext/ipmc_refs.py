"""Resolve the short and module-path cross-references the docstrings use.

The packages' docstrings write ``:class:`State``` or ``:func:`physmodel.estimation.calibration.calibrate```
(the object's home module) while the reference documents each public object once, under the
name users import it by (``physmodel.calibrate``).  For a Python reference Sphinx could not
resolve, :func:`docstring_audit.resolve` tries the current class (with what it inherits) and
module, the object the target names when imported (any documented name for the same object),
and a unique documented name ending in ``.<target>`` (preferring the referring package).

A target listed in ``docstring_debt.json`` as an unresolved reference (a stale module path in a
docstring) is shown as plain text.  Anything else still unresolved, or ambiguous, stays a warning
(an error under ``-W``), and ``python docs/_ext/docstring_policy.py --update`` lists it as debt.
"""

from __future__ import annotations

from docutils import nodes

import docstring_audit
import docstring_policy


def resolve(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "").lstrip(".~!")
    if not target or target.startswith("_"):
        return None
    module = node.get("py:module")
    cls = node.get("py:class")
    chosen = docstring_audit.resolve(target, module, f"{module}.{cls}" if module and cls else cls)
    objects = env.get_domain("py").objects
    if chosen is None or chosen not in objects:
        if target in docstring_policy.UNRESOLVED_REFERENCES:
            return contnode            # known debt: plain text until the docstring is fixed
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
