"""``python -m mitsuba_brdfs presets [list | show MATERIAL --model M [--xml]]``.

``list`` (the default) names the 86 materials of the Ngan et al. 2005 fits and the five
models; ``show`` prints one preset as the dict ``mi.load_dict`` takes (``--xml``: as a
``<bsdf version="3.0.0" ...>`` file, after a comment line saying how to use it). Saved as
a file, the XML loads as it is (``mi.load_file``, ``check h.xml``, or ``<include
filename="h.xml"/>`` inside a scene's ``<shape>``); pasted into a scene, it needs its
``version`` attribute removed (Mitsuba accepts it on the root element only). An unknown name
is refused with the closest one (exit status 2). Writes nothing.
"""
import json

from . import MODELS, XML_VERSION, names, ngan2005, suggest, to_xml

__all__ = ["add_arguments", "run"]


def add_arguments(p):
    p.add_argument("action", nargs="?", default="list", metavar="ACTION",
                   help="list (default) or show")
    p.add_argument("material", nargs="?", metavar="MATERIAL", help="a material (with show)")
    p.add_argument("--model", help=f"one of {', '.join(MODELS)} (with show)")
    p.add_argument("--xml", action="store_true", help="show the preset as a <bsdf> element")


def run(args):
    if args.action not in ("list", "show"):
        raise ValueError(f"presets: unknown action '{args.action}'"
                         f"{suggest(args.action, ('list', 'show'))}; use list or show")
    if args.action == "list":
        print(f"{len(names())} materials (Ngan et al. 2005 fits to MERL), models: "
              f"{', '.join(MODELS)}")
        for name in names():
            print(name)
        return 0
    if args.material is None:
        raise ValueError(f"presets: show needs a MATERIAL ('presets list' names all "
                         f"{len(names())}) and --model (one of {', '.join(MODELS)})")
    if args.material not in names():
        raise ValueError(f"presets: unknown material '{args.material}'"
                         f"{suggest(args.material, names())}; 'presets list' names all "
                         f"{len(names())}")
    if args.model is None:
        raise ValueError(f"presets: show {args.material} needs --model, one of "
                         f"{', '.join(MODELS)} (e.g. presets show {args.material} --model "
                         f"{MODELS[0]})")
    preset = ngan2005(args.model, args.material)
    if args.xml:
        print(f"<!-- {args.material}, {args.model} (Ngan et al. 2005). As a file: check FILE, "
              f"or <include filename=\"FILE\"/> inside a <shape>; pasted into a scene: "
              f"without version=\"{XML_VERSION}\" -->")
        print(to_xml(preset, version=True))
    else:
        print(json.dumps(preset, indent=1))
    return 0
