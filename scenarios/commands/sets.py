"""``ipmc sets``: the named parameter sets and their sources, or one set in full."""

from __future__ import annotations

from ._common import EXIT_OK


def add_parser(sub):
    p = sub.add_parser("sets", help="list named parameter sets or show one")
    p.add_argument("name", nargs="?", help="a set to describe")
    p.add_argument("--json", help="also write the set as JSON to this file")
    p.set_defaults(func=run)

def run(args) -> int:
    from physmodel import available_parameter_sets, describe, get_parameter_set

    if args.name:
        print(describe(get_parameter_set(args.name)))
        if args.json:
            import json

            from physmodel.data.files import atomic_write

            atomic_write(args.json, lambda fh: fh.write(json.dumps(get_parameter_set(args.name).to_dict(), indent=2, default=str)))
        return EXIT_OK
    for n in available_parameter_sets():
        print(f"{n:24s} {get_parameter_set(n).source}")
    return EXIT_OK
