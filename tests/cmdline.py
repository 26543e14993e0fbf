"""Driving the command line from tests: as a user does (``python -m mitsuba_brdfs ...``,
one process per call), or many invocations in one process (``run_many``: the same
``main()``, without paying Python's and Mitsuba's start-up for each), and tiny scenes."""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

#: runs each argv of a JSON list (stdin) through main(); prints [[status, stdout, stderr]]
_DRIVER = r"""
import contextlib, io, json, sys, traceback
from mitsuba_brdfs.__main__ import main
results = []
for argv in json.load(sys.stdin):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as e:
            code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        except BaseException:
            traceback.print_exc()
            code = -1
    results.append([code, out.getvalue(), err.getvalue()])
sys.__stdout__.write("\n@@@" + json.dumps(results))
"""


def _env(extra=None):
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    env.update(extra or {})
    return env


def run_cli(*args, cwd=ROOT, env=None, timeout=300):
    """``python -m mitsuba_brdfs ARGS`` in its own process."""
    return subprocess.run([sys.executable, "-m", "mitsuba_brdfs", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, env=_env(env))


def run_many(cases, cwd=ROOT, env=None, timeout=600, prelude=""):
    """Each argv of ``cases`` through ``main()``, one after the other in one new process
    (``env``: more environment variables; ``prelude``: code run first, e.g. to stub what
    a command would wait on): [(exit status, stdout, stderr)]."""
    r = subprocess.run([sys.executable, "-c", prelude + _DRIVER], cwd=cwd, capture_output=True,
                       text=True, timeout=timeout, env=_env(env),
                       input=json.dumps([[str(a) for a in argv] for argv in cases]))
    assert "@@@" in r.stdout, r.stderr[-3000:]
    return [tuple(x) for x in json.loads(r.stdout.split("@@@")[-1])]


def run_code(code, *args, cwd=ROOT, timeout=300):
    """``python -c CODE ARGS`` (a test's own set-up around ``main()``) in its own process."""
    return subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, env=_env())


def popen(code, *args, cwd=ROOT):
    """``python -c CODE ARGS`` with stderr piped, for tests that signal the process."""
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)], cwd=cwd,
                            stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                            env=_env())


def popen_tty(code, *args, cwd=ROOT):
    """``python -c CODE ARGS`` with stderr on a terminal (a pseudo-terminal), as a user at a
    terminal sees it (progress bars redrawn every 0.1 s, not every 5 s as in a pipe):
    (the process, its stderr as a text stream). ``read_rest`` reads what remains; use
    the process in a ``with`` block (``subprocess.Popen``'s), so that it is killed and
    the terminal closed whatever the test finds."""
    import fcntl
    import pty
    import struct
    import termios
    master, slave = pty.openpty()
    # a terminal of 24 rows and 120 columns (a new one has 0 columns: no room for a bar)
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    try:
        proc = _TtyProcess([sys.executable, "-c", code, *map(str, args)], cwd=cwd,
                           stderr=slave, stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
                           env=_env())
    finally:
        os.close(slave)
    proc.terminal = _Terminal(master)
    return proc, proc.terminal


class _TtyProcess(subprocess.Popen):
    """A process of ``popen_tty``: leaving its ``with`` block kills it if it still runs
    and closes its terminal."""

    def __exit__(self, *exc):
        if self.poll() is None:
            self.kill()
        self.terminal.close()
        return super().__exit__(*exc)


class _Terminal:
    """The reading end of a pseudo-terminal, read unbuffered (``read(n)``: at most n
    characters of what is there; "" once the other end is closed)."""

    def __init__(self, fd):
        self.fd = fd

    def read(self, n=1, timeout=None):
        import select
        if self.fd is None:
            return ""
        if timeout is not None and not select.select([self.fd], [], [], timeout)[0]:
            raise TimeoutError(f"nothing on the terminal for {timeout} s")
        try:
            return os.read(self.fd, n).decode(errors="replace")
        except OSError:   # the other end closed (Linux: EIO)
            return ""

    def close(self):
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def read_rest(stream, timeout=120):
    """What a terminal stream of ``popen_tty`` holds until its process has closed it;
    TimeoutError after ``timeout`` seconds (a process that does not end)."""
    import time
    rest, end = "", time.monotonic() + timeout
    while True:
        try:
            chunk = stream.read(4096, timeout=max(end - time.monotonic(), 0))
        except TimeoutError:
            chunk = None
        if chunk == "":
            return rest
        if chunk is None or time.monotonic() > end:
            raise TimeoutError(f"the process still runs after {timeout} s: {rest[-300:]!r}")
        rest += chunk


def wait_for(stream, marker, proc):
    """Read ``stream`` until ``marker`` (characters: a progress bar redraws its line with
    carriage returns) or the process ends; returns what was read."""
    seen = ""
    while marker not in seen and proc.poll() is None:
        seen += stream.read(1)
    return seen


def scene_xml(path, res=8, spp=2, sampler="independent", pixel_format="rgb", bsdf=None,
              integrator='<integrator type="direct"/>', sensors=((8, 8),), sensor=True):
    """Write a tiny scene (a sphere under a constant sky; parameters $spp and $res) to
    ``path``. ``sensors``: film sizes of extra sensors after the first."""
    bsdf = bsdf or '<bsdf type="diffuse"/>'
    film = ('<film type="hdrfilm"><integer name="width" value="{w}"/>'
            '<integer name="height" value="{h}"/>'
            f'<string name="pixel_format" value="{pixel_format}"/></film>')
    cams = ""
    if sensor:
        sizes = [("$res", "$res")] + [tuple(map(str, s)) for s in sensors[1:]]
        for w, h in sizes:
            cams += (f'<sensor type="perspective"><sampler type="{sampler}">'
                     f'<integer name="sample_count" value="$spp"/></sampler>'
                     + film.format(w=w, h=h) + "</sensor>")
    text = (f'<scene version="3.0.0"><default name="spp" value="{spp}"/>'
            f'<default name="res" value="{res}"/>{integrator}{cams}'
            f'<shape type="sphere"><transform name="to_world"><translate z="5"/></transform>'
            f'{bsdf}</shape><emitter type="constant"/></scene>')
    with open(path, "w") as f:
        f.write(text)
    return str(path)
