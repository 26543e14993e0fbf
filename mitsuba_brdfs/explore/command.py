"""``python -m mitsuba_brdfs explore [SPEC ...]``: the BRDF explorer, served on this machine.

SPEC is what ``check`` takes: a plugin name (this package's, Mitsuba's, or one that a
``--load FILE.py`` registers) or an XML file with a ``<bsdf>`` (or a scene: each BSDF of
its shapes); or a measured file, an RGL file or a MERL file (``measurement``: its RGL file
made once and cached), to which a model can be fitted in the page (``fitting``: as
``fit-measured`` fits, with ``--fit-samples`` and ``--fit-evaluations``). Several
SPECs are overlaid; without one the page opens on
``ashikhmin_shirley``. ``-p KEY=VALUE`` sets a parameter of every SPEC, ``-p SPEC:KEY=VALUE``
of one. An unknown plugin, a bad ``-p``, a file that does not load or a port in use stop
the command with exit status 2 before anything is served; nothing is written but a MERL
file's RGL file, in the cache.

The address printed (and opened) carries the run's token, ``?token=...``, which the API
asks for (``guard``); ``--host`` beyond this machine (``0.0.0.0``) prints a warning.

    python -m mitsuba_brdfs explore ashikhmin_shirley roughplastic -p roughplastic:alpha=0.2
    python -m mitsuba_brdfs explore mybsdf --load mybsdf.py --port 8800 --no-browser
"""
import importlib.util
import socket
import sys
import threading
import webbrowser

from ..arguments import UsageError, add_load, int_range, nonnegative_int, positive_int

__all__ = ["DEFAULT_PORT", "require", "split_params", "bind", "addresses", "add_arguments",
           "run"]

DEFAULT_PORT = 8765


def require():
    """Raise ``UsageError`` naming the pip command if a package of the extra is missing."""
    from . import REQUIRES
    missing = [pkg for mod, pkg in REQUIRES.items() if importlib.util.find_spec(mod) is None]
    if missing:
        raise UsageError(f"explore needs {', '.join(missing)}: pip install "
                         f"'mitsuba_brdfs[explore]' (or pip install {' '.join(missing)})")


def split_params(items, specs):
    """``-p`` items -> {spec: {key: raw value}}: ``SPEC:KEY=VALUE`` for one SPEC, else
    every SPEC. A SPEC: prefix naming no SPEC, or a key given twice for one SPEC (``-p
    alpha=0.1 -p ward:alpha=0.2`` included), is a ``UsageError``."""
    from ..spec import parse_params
    given = {s: [] for s in specs}
    for item in items:
        key = item.partition("=")[0]
        target, colon, name = key.rpartition(":")
        if colon and target:
            if target not in given:
                raise UsageError(f"bad -p {item!r}: {target!r} is not one of the SPECs "
                                 f"({', '.join(specs)})")
            given[target].append(name + item[len(key):])
        else:
            for s in specs:
                given[s].append(item)
    out = {}
    for s, its in given.items():
        try:
            out[s] = parse_params(its)
        except UsageError as e:
            raise UsageError(f"{e} (for {s})" if len(specs) > 1 else str(e)) from None
    return out


def bind(host, port):
    """A listening socket on (host, port); ``UsageError`` naming the port if it is taken."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as e:
        raise UsageError(f"explore: --host {host!r}: {e.strerror}") from None
    family, _, _, _, addr = infos[0]
    sock = socket.socket(family, socket.SOCK_STREAM)
    # as servers do: a port left in TIME_WAIT by a stopped server can be used again, one
    # that another process listens on cannot
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(addr)
    except OSError as e:
        sock.close()
        raise UsageError(f"explore: port {port} on {host} is in use ({e.strerror}); choose "
                         f"another with --port N (--port 0: any free port)") from None
    sock.listen(64)
    return sock


def add_arguments(p):
    p.add_argument("spec", nargs="*", metavar="SPEC",
                   help="BSDFs to show: a plugin name (this package's, Mitsuba's, or one "
                        "registered by --load), an XML file with a <bsdf>, or a measured "
                        "RGL or MERL file (default: ashikhmin_shirley); several are overlaid")
    p.add_argument("-p", dest="params", action="append", default=[],
                   metavar="[SPEC:]KEY=VALUE",
                   help="a parameter, as check takes it (a number, r,g,b, true/false, a "
                        "string), of every SPEC or of SPEC: (repeatable)")
    add_load(p)
    p.add_argument("--variant", default="llvm_ad_rgb",
                   help="Mitsuba variant, a JIT one (default: llvm_ad_rgb)")
    p.add_argument("--port", type=int_range(0, 65535), default=DEFAULT_PORT,
                   help=f"port to serve on (default: {DEFAULT_PORT}; 0: any free port)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to serve on (default: 127.0.0.1, this machine only; "
                        "another, e.g. 0.0.0.0, serves the network, with a warning)")
    p.add_argument("--no-browser", action="store_true",
                   help="do not open the page in a browser")
    from .fitting import EVALUATIONS, SAMPLES
    p.add_argument("--fit-samples", type=positive_int, default=SAMPLES,
                   help="the page's fits: fit-measured's --samples (default: %(default)s)")
    p.add_argument("--fit-evaluations", type=nonnegative_int, default=EVALUATIONS,
                   help="the page's fits: fit-measured's --evaluations, a budget per stage "
                        "(default: %(default)s)")


def _set_variant(variant):
    import mitsuba as mi
    if not variant.startswith(("llvm_", "cuda_")) or "polarized" in variant:
        raise UsageError(f"explore needs an unpolarized JIT variant (llvm_ad_rgb, "
                         f"llvm_ad_spectral, cuda_ad_rgb, ...), not {variant!r}")
    from ..variant import set_variant
    set_variant(variant)  # the plugins registered in it too
    return mi


def run(args):
    require()
    from ..spec import locate
    specs = list(dict.fromkeys(args.spec or ["ashikhmin_shirley"]))
    params = split_params(args.params, specs)
    for spec in specs:  # a file that is not there: refused before anything is served
        locate(spec)
    sock = bind(args.host, args.port)  # before any work: a port in use stops here
    try:
        _set_variant(args.variant)
        from ..variant import run_file
        for path in args.load:
            run_file(path)
        from .entries import make_entries
        from .server import app, plotly_js
        from .session import MAX_ENTRIES, PALETTE, Explorer
        plotly_js()
        found = []
        for spec in specs:
            found += make_entries(spec, params[spec], len(found), PALETTE)
        for e in found:   # where a MERL file's RGL file went (the page says it too)
            if e.measured is not None and e.measured["kind"] == "merl" \
                    and not e.measured["cached"]:
                print(f"explore: {e.label}: {e.measured['note']}", file=sys.stderr,
                      flush=True)
        if len(found) > MAX_ENTRIES:
            raise UsageError(f"explore shows at most {MAX_ENTRIES} BSDFs at once; the "
                             f"SPECs give {len(found)}")
        explorer = Explorer(found, args.variant, specs, args.fit_samples,
                            args.fit_evaluations)
        port = sock.getsockname()[1]
        application = app(explorer, args.host, port)
        return _serve(application, sock, args, len(found))
    finally:
        sock.close()


def addresses(host, port, token):
    """(the address that works on this machine, the one for other machines or None)."""
    from .guard import is_loopback, is_wildcard
    query = f"/?token={token}"
    if is_wildcard(host):
        local = "[::1]" if host == "::" else "127.0.0.1"
        return f"http://{local}:{port}{query}", f"http://{socket.gethostname()}:{port}{query}"
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{port}{query}"
    return url, (None if is_loopback(host) else url)


def _serve(application, sock, args, count):
    import uvicorn
    port = sock.getsockname()[1]
    url, remote = addresses(args.host, port, application.token)
    print(f"explore: {count} BSDF(s) at {url} (variant {args.variant}; Ctrl-C stops)",
          flush=True)
    if remote is not None:
        print(f"explore: warning: --host {args.host} serves beyond this machine: whoever "
              f"can reach port {port} and has the address with its token ({remote}) can "
              f"change the BSDFs and have the XML files of this folder loaded; the "
              f"traffic is plain HTTP, not encrypted", file=sys.stderr, flush=True)
    if not args.no_browser:
        threading.Timer(0.5, webbrowser.open, [url]).start()
    from .server import config
    server = uvicorn.Server(config(application))
    server.run(sockets=[sock])
    print("explore: stopped", file=sys.stderr)
    return 0
