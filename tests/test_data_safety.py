"""Never lose data, never accept a broken tyre silently (issue 14).

Every command is driven in-process through :func:`mftire.cli.main` with the usual
slips of hand.  For each case: the exact exit code, a one-line message, the inputs
unchanged (SHA-256 before and after) and no file left behind (the work folder's
listing before and after).
"""

from __future__ import annotations

import hashlib
import os
import socket
import stat
import threading
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler
from hypothesis import given, settings
from hypothesis import strategies as st

import mftire
from mftire.cli import main
from mftire.errors import MftireTirWarning, MftireUnitWarning
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.atomic import atomic_path
from mftire.iotools.output import OutputPlan, figure_format
from mftire.iotools.tir import read_tir
from mftire.iotools.tir_checks import TirCheckError, check_parameters

MF61 = REFERENCE_TYRES["MF61"]


# --------------------------------------------------------------------------- helpers


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _listing(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


@pytest.fixture(scope="module")
def ws(tmp_path_factory) -> Path:
    """A work folder: a tyre, an evaluate input, sweep data, an FE braking table."""
    d = tmp_path_factory.mktemp("safety")
    (d / "tyre.tir").write_bytes(MF61.read_bytes())
    (d / "points.csv").write_text("Fz,kappa,alpha,gamma\n4000,-0.1,0.05,0\n6000,0,0.1,0.02\n")
    tyre = read_tir(MF61)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df = synthetic_sweeps(tyre, [4000.0, 6000.0], [0.0], n_kappa=15, n_alpha=15, n_combined=5, seed=1)
    df.to_csv(d / "sweeps.csv", index=False)
    (d / "fe_braking.csv").write_text("kind,Fz,Vx,P,kappa,Fx\nbraking,4000,10,2e5,-0.05,-3000\n")
    _tiny_ttc(d / "run.dat")
    return d


def _tiny_ttc(path: Path) -> None:
    """A raw TTC-style run: two load levels, one slip-angle sweep each (SAE axes, metric units)."""
    from mftire.iotools.rig import TTC_CHANNELS

    units = "s kph rpm deg deg cm cm kPa N N N N-m N-m - - degC degC degC degC degC -".split()
    rows, t = [], 0.0
    for fz in (-1000.0, -1500.0):
        for k in range(40):
            v = dict(ET=t, V=40.0, N=300.0, SA=-6 + 12 * k / 39, IA=0.0, RL=30.0, RE=31.0, P=80.0, FX=0.0,
                     FY=100.0 * (k - 20), FZ=fz, MX=0.0, MZ=0.5 * (k - 20), NFX=0.0, NFY=0.0, RST=30.0, TSTI=50.0,
                     TSTC=51.0, TSTO=52.0, AMBTMP=25.0, SR=0.0)
            rows.append("\t".join(f"{v[c]:g}" for c in TTC_CHANNELS))
            t += 0.1
    path.write_text("title\n" + "\t".join(TTC_CHANNELS) + "\n" + "\t".join(units) + "\n" + "\n".join(rows) + "\n")


class Run:
    """One CLI run in a fresh copy of the work folder, with the safety assertions."""

    def __init__(self, ws: Path, tmp_path: Path, capsys) -> None:
        self.root = tmp_path / "w"
        self.root.mkdir()
        for p in ws.iterdir():
            (self.root / p.name).write_bytes(p.read_bytes())
        self.capsys = capsys

    def p(self, name: str) -> str:
        return str(self.root / name)

    def __call__(self, argv: list[str], rc: int, *fragments: str, created: set[str] = frozenset()) -> str:
        before = _listing(self.root)
        sums = {p: _sha(p) for p in self.root.rglob("*") if p.is_file() and not p.is_symlink()}
        self.capsys.readouterr()
        got = main(argv)
        cap = self.capsys.readouterr()
        assert got == rc, cap.err
        if rc == 2:
            lines = cap.err.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith(f"mftire {argv[0]}: error: "), cap.err
            for f in fragments:
                assert f in lines[0], lines[0]
            assert _listing(self.root) == before  # nothing left behind, nothing created
        for p, h in sums.items():  # inputs (and every other file) unchanged
            if p.exists() and str(p.relative_to(self.root)) not in created:
                assert _sha(p) == h, p
        assert not [n for n in _listing(self.root) if n.endswith(".tmp") or "/.mftire" in n]
        return cap.err


@pytest.fixture()
def run(ws, tmp_path, capsys) -> Run:
    return Run(ws, tmp_path, capsys)


def _commands(r: Run, out: str) -> dict[str, list[str]]:
    """Every command with its inputs from the work folder, writing to ``out``."""
    return {
        "evaluate": ["evaluate", r.p("tyre.tir"), "--input", r.p("points.csv"), "--output", out],
        "convert": ["convert", r.p("tyre.tir"), out],
        "plot": ["plot", r.p("tyre.tir"), "--output", out],
        "plot-csv": ["plot", r.p("tyre.tir"), "--output", r.p("new.png"), "--csv", out],
        "fit": ["fit", r.p("sweeps.csv"), "--template", r.p("tyre.tir"), "--output", out],
        "fit-report": ["fit", r.p("sweeps.csv"), "--template", r.p("tyre.tir"), "--output", r.p("new.tir"),
                       "--report", out],
        "export-fmu": ["export-fmu", r.p("tyre.tir"), "--output", out],
        "diagnose": ["diagnose", r.p("sweeps.csv"), "--tir", r.p("tyre.tir"), "--output", out],
        "compare": ["compare", "--tir", r.p("tyre.tir"), "--data", r.p("sweeps.csv"), "--output", out],
        "demo": ["demo", "--output", out, "--quick"],
        "fe-sweep": ["fe", "sweep", "--kind", "braking", "--Fz", "4000", "--Vx", "10", "--points", "5",
                     "--output", out],
        "fe-campaign": ["fe", "campaign", "--quick", "--output", out],
        "fe-identify": ["fe", "identify", r.p("fe_braking.csv"), "--mu-p", "1", "--output", out],
        "import": ["import", r.p("run.dat"), "--output", out],
        "import-report": ["import", r.p("run.dat"), "--output", r.p("new.csv"), "--report", out],
    }


FOLDER_OUTPUTS = {"fit-report", "diagnose", "compare", "demo", "fe-campaign"}
ALL = ["evaluate", "convert", "plot", "plot-csv", "fit", "fit-report", "export-fmu", "diagnose", "compare", "demo",
       "fe-sweep", "fe-campaign", "fe-identify", "import", "import-report"]
INPUTS = {"evaluate": ["tyre.tir", "points.csv"], "convert": ["tyre.tir"], "plot": ["tyre.tir"],
          "plot-csv": ["tyre.tir"], "fit": ["sweeps.csv", "tyre.tir"], "export-fmu": ["tyre.tir"],
          "fe-identify": ["fe_braking.csv"], "fit-report": ["sweeps.csv"], "diagnose": ["sweeps.csv", "tyre.tir"],
          "compare": ["sweeps.csv", "tyre.tir"], "import": ["run.dat"], "import-report": ["run.dat"]}


# --------------------------------------------------------------------------- outputs


@pytest.mark.parametrize("cmd,inp", [(c, i) for c, ins in INPUTS.items() for i in ins])
def test_output_equal_to_an_input_is_refused(run, cmd, inp):
    argv = _commands(run, run.p(inp))[cmd]
    if cmd in FOLDER_OUTPUTS:
        run(argv, 2, run.p(inp), "not a folder")
    elif cmd == "plot":
        run(argv, 2, "not a figure format")  # a .tir/.csv is no figure; refused before anything else
    else:
        run(argv, 2, "output is the input file", run.p(inp))


@pytest.mark.parametrize("cmd", ["evaluate", "convert", "fit", "export-fmu"])
def test_output_linked_to_an_input_is_refused(run, cmd):
    os.symlink(run.p("tyre.tir"), run.p("sym.tir"))
    os.link(run.p("tyre.tir"), run.p("hard.tir"))
    run(_commands(run, run.p("sym.tir"))[cmd], 2, "output is the input file")
    run(_commands(run, run.p("hard.tir"))[cmd], 2, "output is the input file")


def test_outputs_of_one_command_must_differ(run):
    run(["plot", run.p("tyre.tir"), "--output", run.p("a.png"), "--csv", run.p("a.png")], 2, "also output")


@pytest.mark.parametrize("cmd", ALL)
def test_existing_output_needs_force(run, cmd):
    if cmd in FOLDER_OUTPUTS:
        os.mkdir(run.p("old"))
        Path(run.p("old/keep.txt")).write_text("mine")
        run(_commands(run, run.p("old"))[cmd], 2, "folder is not empty; use --force")
    else:
        Path(run.p("old.png")).write_text("mine")
        run(_commands(run, run.p("old.png"))[cmd], 2, "exists; use --force")
    assert Path(run.p("old/keep.txt") if cmd in FOLDER_OUTPUTS else run.p("old.png")).read_text() == "mine"


@pytest.mark.parametrize("cmd", ALL)
def test_output_under_a_regular_file_is_refused_before_any_work(run, cmd):
    """'Unwritable folder', root-proof: the parent of the output is a regular file."""
    out = os.path.join(run.p("points.csv"), "sub", "out.png" if cmd not in FOLDER_OUTPUTS else "dir")
    run(_commands(run, out)[cmd], 2, "is not a folder")


@pytest.mark.parametrize("cmd", ["evaluate", "fit", "compare"])
def test_output_in_an_unwritable_file_system_is_refused(run, cmd):
    """/proc takes no new files, even from root."""
    run(_commands(run, "/proc/mftire-test/out")[cmd], 2, "not writable")


def test_fit_checks_the_report_folder_before_writing_the_tir(run):
    argv = _commands(run, os.path.join(run.p("points.csv"), "report"))["fit-report"]
    run(argv, 2, "is not a folder")
    assert not Path(run.p("new.tir")).exists()


@pytest.mark.parametrize("cmd", ["evaluate", "convert", "plot", "plot-csv", "fe-sweep", "export-fmu", "fit"])
def test_dangling_symlink_socket_and_folder_outputs_are_refused(run, cmd):
    os.symlink(run.p("nowhere/x"), run.p("dangling.png"))
    run(_commands(run, run.p("dangling.png"))[cmd], 2, "symbolic link to a missing file")
    os.mkdir(run.p("adir.png"))
    run(_commands(run, run.p("adir.png"))[cmd], 2, "is a folder")
    sock = socket.socket(socket.AF_UNIX)
    try:
        sock.bind(run.p("s.png"))
        run(_commands(run, run.p("s.png"))[cmd], 2, "is a socket")
    finally:
        sock.close()


def test_symlink_to_a_regular_file_replaces_the_target_with_force(run):
    Path(run.p("target.csv")).write_text("old")
    os.symlink(run.p("target.csv"), run.p("link.csv"))
    run(_commands(run, run.p("link.csv"))["evaluate"], 2, "exists; use --force")
    run(_commands(run, run.p("link.csv"))["evaluate"] + ["--force"], 0, created={"target.csv"})
    assert os.path.islink(run.p("link.csv"))
    assert pd.read_csv(run.p("target.csv")).shape == (2, 34)


def _char_device(path: str) -> None:
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # a /dev/null of our own
        with open(path, "wb") as fh:
            fh.write(b"x")
    except OSError as exc:
        pytest.skip(f"cannot make a character device here: {exc}")


@pytest.mark.parametrize("cmd", ["evaluate", "convert", "plot-csv", "fe-sweep", "fit", "export-fmu"])
def test_character_device_is_written_through(run, cmd):
    if cmd == "export-fmu":
        pytest.importorskip("fmpy")
        from conftest import have_c_compiler

        if not have_c_compiler():
            pytest.skip("no C compiler")
    dev = run.p("null")
    _char_device(dev)
    run(_commands(run, dev)[cmd], 0)
    assert stat.S_ISCHR(os.stat(dev).st_mode)


def test_dev_null_stays_a_device(run):
    run(_commands(run, "/dev/null")["evaluate"], 0)
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


@pytest.mark.parametrize("cmd", ["evaluate", "convert", "plot"])
def test_fifo_is_written_through(run, cmd):
    fifo = run.p("pipe.svg")
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(Path(fifo).read_bytes()), daemon=True)
    reader.start()
    run(_commands(run, fifo)[cmd], 0)
    reader.join(10)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    data = got[0]
    if cmd == "evaluate":
        assert data.startswith(b"Fz,kappa,alpha,gamma,Fx,Fy,Fz_model")
    elif cmd == "convert":
        assert read_tir(MF61).flat()["PKY1"] == float(
            next(ln for ln in data.decode().splitlines() if ln.startswith("PKY1")).split("=")[1].split("$")[0])
    else:
        assert data.lstrip().startswith(b"<?xml") and b"<svg" in data  # SVG, from the suffix


@pytest.mark.parametrize("cmd", ["evaluate", "convert", "plot", "plot-csv", "fe-sweep"])
def test_missing_folders_are_created(run, cmd):
    out = run.p("a/b/out.svg" if cmd == "plot" else "a/b/out.csv")
    run(_commands(run, out)[cmd], 0, created=set())
    assert Path(out).stat().st_size > 0


def test_figure_format_follows_the_suffix(run):
    for name, magic in (("f.pdf", b"%PDF"), ("f.png", b"\x89PNG"), ("f.svg", b"<?xml")):
        run(_commands(run, run.p(name))["plot"], 0)
        assert Path(run.p(name)).read_bytes().startswith(magic)
    run(_commands(run, run.p("f.gif"))["plot"], 2, "'.gif' is not a figure format")
    with pytest.raises(mftire.errors.MftireInputError):
        figure_format("noext")


def test_failed_write_leaves_nothing(tmp_path):
    target = tmp_path / "deep" / "er" / "out.csv"
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        Path(tmp).write_text("half")
        raise RuntimeError("disk full")
    assert list(tmp_path.iterdir()) == []  # neither the temp file nor the created folders


def test_output_plan_api(tmp_path):
    a = tmp_path / "a.csv"
    a.write_text("x")
    plan = OutputPlan([a], force=True)
    with pytest.raises(mftire.errors.MftireInputError, match="is the input"):
        plan.file(a)
    assert plan.file(tmp_path / "b.csv") == str(tmp_path / "b.csv")
    assert plan.file("-", stdout=True) == "-"


def test_broken_pipe_exits_quietly(run, monkeypatch):
    import io

    class Closed(io.StringIO):
        def write(self, s):
            raise BrokenPipeError(32, "Broken pipe")

        def fileno(self):
            raise io.UnsupportedOperation("fileno")

    monkeypatch.setattr("sys.stdout", Closed())
    assert main(_commands(run, "-")["evaluate"]) == 141
    assert run.capsys.readouterr().err == ""


def test_version_and_help_texts(capsys):
    import argparse

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"mftire {mftire.__version__}"
    from mftire.cli import build_parser

    def walk(parser, name):
        assert parser.description, name
        for a in parser._actions:
            if isinstance(a, argparse._SubParsersAction):
                for n, sp in a.choices.items():
                    walk(sp, f"{name} {n}")
            else:
                assert a.help, f"{name} {a.option_strings or a.dest}"

    walk(build_parser(), "mftire")


# --------------------------------------------------------------------------- broken .tir files


def _variant(kind: str) -> str:
    text = MF61.read_text()
    lines = text.splitlines(keepends=True)
    if kind == "truncated":  # half the lines
        return "".join(lines[: len(lines) // 2])
    if kind == "truncated-midline":  # half the bytes, cut inside a line
        return text[: len(text) // 2]
    if kind == "sectionless":
        out, skip = [], False
        for ln in lines:
            if ln.startswith("["):
                skip = ln.startswith("[LONGITUDINAL_COEFFICIENTS]")
            if not skip:
                out.append(ln)
        return "".join(out)
    key, value = {"nan": ("PDX1", "nan"), "negative": ("UNLOADED_RADIUS", "-0.3"), "fnomin0": ("FNOMIN", "0"),
                  "inch": ("LENGTH", "'inch'")}[kind]
    return "".join(f"{key} = {value}\n" if ln.split("=")[0].strip() == key else ln for ln in lines)


BROKEN = {
    "truncated": "required section(s) [LATERAL_COEFFICIENTS], [ALIGNING_COEFFICIENTS] missing (is the file truncated?)",
    "sectionless": "required section(s) [LONGITUDINAL_COEFFICIENTS] missing",
    "nan": "non-finite value(s): PDX1 = nan",
    "negative": "UNLOADED_RADIUS = -0.3 must be > 0",
    "fnomin0": "FNOMIN = 0 must be > 0",
    "truncated-midline": "expected KEY = value",
}
TIR_READERS = ["evaluate", "convert", "plot", "fit", "export-fmu", "diagnose", "compare", "info"]


def _tir_argv(r: Run, cmd: str) -> list[str]:
    if cmd == "info":
        return ["info", r.p("tyre.tir")]
    return _commands(r, r.p("new.out" if cmd not in ("plot", "diagnose", "compare") else
                            {"plot": "new.png", "diagnose": "diag", "compare": "cmp"}[cmd]))[cmd]


@pytest.mark.parametrize("kind", sorted(BROKEN))
@pytest.mark.parametrize("cmd", TIR_READERS)
def test_broken_tir_is_an_error_naming_the_file(run, cmd, kind):
    Path(run.p("tyre.tir")).write_text(_variant(kind))
    if cmd == "info" and kind != "truncated-midline":  # info prints every failed check, then exits 2
        before = _sha(Path(run.p("tyre.tir")))
        run.capsys.readouterr()
        assert main(_tir_argv(run, cmd)) == 2
        cap = run.capsys.readouterr()
        assert f"  error: {BROKEN[kind]}" in cap.out and cap.err == ""
        assert _sha(Path(run.p("tyre.tir"))) == before
        return
    err = run(_tir_argv(run, cmd), 2, run.p("tyre.tir"), BROKEN[kind])
    assert "Traceback" not in err


def test_broken_tir_in_python():
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        for kind, msg in BROKEN.items():
            p = Path(d) / f"{kind}.tir"
            p.write_text(_variant(kind))
            with pytest.raises(mftire.errors.MftireError) as exc:
                mftire.load(p)
            assert msg in str(exc.value) and str(p) in str(exc.value)


def test_unit_mismatched_tir_warns_with_a_hint(run):
    Path(run.p("tyre.tir")).write_text(_variant("inch"))
    err = run(_commands(run, run.p("o.csv"))["evaluate"], 0, created={"o.csv"})
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mftire evaluate: warning: ")
    assert "NOMPRES = 4.03e+08 Pa" in lines[0] and "LENGTH = 'inch'" in lines[0]
    err = run(["info", run.p("tyre.tir")], 0)
    assert run(["info", run.p("tyre.tir"), "--strict"], 1) == ""
    with pytest.warns(MftireTirWarning, match="implausible after unit conversion"):
        mftire.load(run.p("tyre.tir"))
    with pytest.raises(TirCheckError):
        check_parameters(read_tir(run.p("tyre.tir"))).raise_errors(strict=True)


def test_info_prints_defaulted_keys_and_checks(run):
    run.capsys.readouterr()
    assert main(["info", run.p("tyre.tir")]) == 0
    out = run.capsys.readouterr().out
    assert "checks:\n  all passed" in out
    # a renamed section whose keys are renamed too (keys of a missing section found elsewhere are used: no warning)
    Path(run.p("tyre.tir")).write_text(_variant("sectionless").replace("[ROLLING_COEFFICIENTS]", "[ROLLING_X]")
                                       .replace("QSY", "XSY"))
    assert main(["info", run.p("tyre.tir")]) == 2
    out = run.capsys.readouterr().out
    assert "error: required section(s) [LONGITUDINAL_COEFFICIENTS] missing" in out
    assert "warning: optional section(s) [ROLLING_COEFFICIENTS] missing; 8 key(s) take default values" in out
    assert "[ROLLING_COEFFICIENTS] QSY1, QSY2" in out


def test_shipped_tir_files_pass_every_check():
    root = Path(__file__).resolve().parents[1]
    files = [*root.glob("tirfiles/**/*.tir"), *root.glob("tests/data/tir/**/*.tir"), root / "mftire/data/default.tir"]
    assert len(files) >= 19
    for f in files:
        rep = check_parameters(read_tir(f))
        assert rep.errors == [] and rep.warnings == [], f
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            mftire.load(f)


# --------------------------------------------------------------------------- inputs


def test_degrees_and_kn_warn_once_as_one_line(run):
    Path(run.p("deg.csv")).write_text("Fz,kappa,alpha,gamma\n4000,0,5,0\n4000,0,-8,0\n")
    argv = ["evaluate", run.p("tyre.tir"), "--input", run.p("deg.csv"), "--output", run.p("o.csv")]
    err = run(argv, 0, created={"o.csv"})
    lines = [ln for ln in err.splitlines() if "MftireUnitWarning" in ln or "look like degrees" in ln]
    assert lines == ["mftire evaluate: warning: slip angle alpha up to 8 rad (458 deg): alpha is in radians; "
                     "values above 1.5 rad look like degrees (convert with numpy.deg2rad)"]
    assert all(ln.startswith("mftire evaluate: warning: ") for ln in err.splitlines())  # no source lines
    Path(run.p("kn.csv")).write_text("Fz,kappa,alpha,gamma\n4,0,0.1,0\n6,0,0.1,0\n")
    argv = ["evaluate", run.p("tyre.tir"), "--input", run.p("kn.csv"), "--output", run.p("o.csv"), "--force"]
    err = run(argv, 0, created={"o.csv"})
    assert "the values look like kN" in err and len(err.strip().splitlines()) == 1


@pytest.mark.filterwarnings("ignore:.*saturated")
def test_unit_warnings_in_python_modes_and_rate():
    tyre = mftire.load(MF61)
    for mode in (111, 211):
        t = mftire.load(MF61)
        with pytest.warns(MftireUnitWarning, match="look like degrees"):
            t.evaluate(4000.0, 0.0, 5.0, mode=mode)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(5):
            tyre.evaluate(4.0, 0.0, 0.1)
    assert sum(issubclass(w.category, MftireUnitWarning) for w in caught) == 1  # once per tyre and cause
    with warnings.catch_warnings():
        warnings.simplefilter("error", MftireUnitWarning)
        tyre.evaluate(np.array([100.0, 4000.0]), 0.0, np.array([0.1, 1.2]))  # a real batch: no warning


@pytest.mark.parametrize("kw,guess", [("vx", "Vx"), ("pressure", "P"), ("Fzz", "Fz"), ("speed", "Vx"),
                                      ("alfa", "alpha"), ("Omega", "omega")])
def test_misspelled_keywords_raise_type_error_with_suggestion(kw, guess):
    tyre = mftire.load(MF61)
    with pytest.raises(TypeError, match=f"unexpected keyword argument '{kw}'; did you mean '{guess}'"):
        tyre.evaluate(4000.0, 0.0, 0.0, **{kw: 1.0})


def test_extension_variables_are_checked():
    from test_fmu_guards import extension_entries

    params = read_tir(MF61)
    for k, v in extension_entries(["temperature"]).items():
        params.set(k, v, section="MFTIRE_EXTENSIONS")
    tyre = mftire.Tyre(params)
    assert tyre.required_variables == ["temperature"]
    tyre.evaluate(4000.0, -0.1, 0.0, temperature=60.0)
    with pytest.raises(TypeError, match="'temprature'; did you mean 'temperature'"):
        tyre.evaluate(4000.0, -0.1, 0.0, temprature=60.0)
    with pytest.raises(TypeError, match="extensions take: temperature"):
        tyre.evaluate(4000.0, -0.1, 0.0, temperature=60.0, humidity=0.5)


# --------------------------------------------------------------------------- evaluate CSV, small things


def test_evaluate_names_model_outputs_apart_and_writes_shortest_floats(run):
    df = pd.DataFrame({"Fz": [4000.0, 6000.0], "kappa": [-0.1, 0.0], "alpha": [0.05, 0.1], "gamma": [0.0, 0.02],
                       "Fx": [-3000.5, 10.25], "Fy": [1.0, 2.0]})
    df.to_csv(run.p("meas.csv"), index=False)
    argv = ["evaluate", run.p("tyre.tir"), "--input", run.p("meas.csv"), "--output", run.p("o.csv")]
    run(argv, 0, created={"o.csv"})
    out = pd.read_csv(run.p("o.csv"))
    assert list(out.columns[:8]) == ["Fz", "kappa", "alpha", "gamma", "Fx", "Fy", "Fx_model", "Fy_model"]
    assert out["Fx"].tolist() == [-3000.5, 10.25]
    ref = mftire.load(MF61).evaluate(df["Fz"], df["kappa"], df["alpha"], df["gamma"])
    np.testing.assert_array_equal(out["Fx_model"], ref["Fx"])  # bit-exact round trip
    text = Path(run.p("o.csv")).read_text().splitlines()[1]
    assert text.startswith("4000.0,-0.1,0.05,0.0,-3000.5,1.0,")  # shortest repr, not %.17g
    assert all(len(c) <= 24 for c in text.split(","))


def test_fit_without_force_channel_is_an_error(run):
    df = pd.read_csv(run.p("sweeps.csv")).drop(columns=["Fx", "Fy", "Mz", "Mx", "My"], errors="ignore")
    df.to_csv(run.p("noforce.csv"), index=False)
    argv = ["fit", run.p("noforce.csv"), "--template", run.p("tyre.tir"), "--output", run.p("f.tir")]
    run(argv, 2, "no stage could be fitted", "nothing written")


def test_diagnose_holdout_level_must_exist(run):
    argv = _commands(run, run.p("diag"))["diagnose"] + ["--holdout", "Fz=4000,5000", "--permutations", "9"]
    run(argv, 2, "--holdout Fz: no rows at 5000")


@needs_c_compiler
def test_export_fmu_overwrite_with_force(run):
    argv = _commands(run, run.p("t.fmu"))["export-fmu"]
    run(argv, 0, created={"t.fmu"})
    run(argv, 2, "exists; use --force")
    run(argv + ["--force"], 0, created={"t.fmu"})


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=20))
def test_evaluate_table_writes_shortest_exact_floats(values):
    """Property: every float written by ``evaluate`` reads back bit-exactly, in its shortest repr."""
    import io

    from mftire.cli import evaluate_columns

    buf = io.StringIO()
    evaluate_columns(pd.DataFrame({"Fz": values, "Fx": values}), 1).to_csv(buf, index=False)
    lines = buf.getvalue().splitlines()
    back = pd.read_csv(io.StringIO(buf.getvalue()))
    assert lines[0] == "Fz,Fx"
    assert [np.float64(v).tobytes() for v in back["Fx"]] == [np.float64(v).tobytes() for v in values]
    assert all(cell == repr(float(v)) for line, v in zip(lines[1:], values, strict=True)
               for cell in line.split(",")[:1])


def test_dev_stdout_redirected_by_the_shell_is_written_through(run):
    """``--output /dev/stdout >> log`` appends to the log (the descriptor is written, not reopened)."""
    import subprocess
    import sys

    log = Path(run.p("log.csv"))
    log.write_text("kept\n")
    cmd = (f"{sys.executable} -m mftire.cli evaluate {run.p('tyre.tir')} --input {run.p('points.csv')} "
           f"--output /dev/stdout >> {log}")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    res = subprocess.run(cmd, shell=True, env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    lines = log.read_text().splitlines()
    assert lines[0] == "kept" and lines[1].startswith("Fz,kappa,alpha,gamma,Fx") and len(lines) == 4


# =========================================================================== issue 24: second round
#
# The adversarial families: output (out), names, .tir (tir), data, API (api), FMU (fmu); the test
# names carry the family.  Every CLI case asserts the exit code, a one-line message, unchanged
# inputs and no file left behind (Run above), unless it says otherwise.


def _tir_with(path: Path, values: dict, section: str | None = None) -> Path:
    """MF61 with ``values`` set (SI), written to ``path``."""
    from mftire.iotools.tir import write_tir

    params = read_tir(MF61)
    for k, v in values.items():
        params.set(k, v, section=section)
    write_tir(params, path)
    return path


# --------------------------------------------------------------------------- out: one write path

FILE_COMMANDS = ["evaluate", "convert", "plot-csv", "fit", "export-fmu", "fe-sweep", "fe-identify", "import",
                 "import-report"]


# ``fit --output DIR/`` is the batch form (one .tir per input in DIR, mftire.batch): a folder there is meant
@pytest.mark.parametrize("cmd", [c for c in FILE_COMMANDS if c != "fit"])
def test_out_trailing_slash_on_a_file_output_is_refused_up_front(run, cmd):
    run(_commands(run, run.p("newdir") + "/")[cmd], 2, "names a folder; this output is a file")


def test_out_import_report_and_output_must_differ(run):
    run(["import", run.p("run.dat"), "--output", run.p("x.csv"), "--report", run.p("x.csv")], 2, "also output")


def test_out_fit_output_and_report_folder_must_differ(run):
    argv = ["fit", run.p("sweeps.csv"), "--template", run.p("tyre.tir"), "--output", run.p("x"), "--report", run.p("x")]
    run(argv, 2, "the same file is also output")


@pytest.mark.parametrize("sign", ["Fy=2", "Fy=0", "Fy=x", "=-1"])
def test_data_import_sign_must_be_a_sign(run, sign):
    run(["import", run.p("run.dat"), "--output", run.p("i.csv"), "--sign", sign], 2, "expected COLUMN=-1 or COLUMN=1")


def test_out_import_writes_the_table_and_the_report_apart(run):
    import json

    argv = ["import", run.p("run.dat"), "--output", run.p("s.csv"), "--report", run.p("r.json")]
    run(argv, 0, created={"s.csv", "r.json"})
    table = pd.read_csv(run.p("s.csv"))
    assert {"Fz", "alpha", "Fy"} <= set(table.columns) and len(table) > 40
    assert json.loads(Path(run.p("r.json")).read_text())["n_sweeps"] == 2
    run(argv, 2, "exists; use --force")
    run(argv + ["--force"], 0, created={"s.csv", "r.json"})


def _appearing(monkeypatch, content: bytes = b"theirs") -> list[str]:
    """Another run writes the output while this one works: the file appears just before the final rename."""
    from mftire.iotools import output

    real, hit = output.final_rename, []

    def racing(tmp: str, path: str) -> None:
        if not hit:
            hit.append(path)
            Path(path).write_bytes(content)
        real(tmp, path)

    monkeypatch.setattr(output, "final_rename", racing)
    return hit


@pytest.mark.parametrize("force", [False, True])
@pytest.mark.parametrize("cmd", ["convert", "evaluate", "import", "fit"])
def test_out_a_file_that_appears_meanwhile_is_not_replaced_without_force(run, monkeypatch, cmd, force):
    out = run.p("out.csv" if cmd in ("evaluate", "import") else "out.tir")
    argv = _commands(run, out)[cmd] + (["--force"] if force else [])
    hit = _appearing(monkeypatch)
    run.capsys.readouterr()
    rc = main(argv)
    err = run.capsys.readouterr().err
    assert hit == [out] or os.path.realpath(hit[0]) == os.path.realpath(out)
    if force:
        assert rc == 0 and Path(out).read_bytes() != b"theirs"
    else:
        assert rc == 2 and Path(out).read_bytes() == b"theirs"  # the other run's result is kept
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "appeared while this command ran" in lines[0] and "--force" in lines[0]
    assert not [n for n in _listing(run.root) if n.endswith(".tmp") or "/.mftire" in n]


def test_out_rename_noreplace(tmp_path):
    from mftire.iotools.output import rename_noreplace

    (tmp_path / "a").write_text("new")
    (tmp_path / "b").write_text("old")
    with pytest.raises(FileExistsError):
        rename_noreplace(str(tmp_path / "a"), str(tmp_path / "b"))
    assert (tmp_path / "a").read_text() == "new" and (tmp_path / "b").read_text() == "old"
    rename_noreplace(str(tmp_path / "a"), str(tmp_path / "c"))
    assert not (tmp_path / "a").exists() and (tmp_path / "c").read_text() == "new"


def test_out_a_command_writes_only_its_checked_outputs(tmp_path):
    from mftire.iotools.atomic import write_text_atomic
    from mftire.iotools.output import command_scope

    inp = tmp_path / "in.csv"
    inp.write_text("x")
    with command_scope():
        plan = OutputPlan([inp], force=False)
        plan.folder(tmp_path / "rep")
        plan.file(tmp_path / "out.csv")
        write_text_atomic(tmp_path / "rep" / "anything.md", "ok")  # inside the checked folder
        write_text_atomic(tmp_path / "out.csv", "1")
        write_text_atomic(tmp_path / "out.csv", "2")  # a file this run wrote may be rewritten
        with pytest.raises(mftire.errors.MftireInputError, match="not an output of this command"):
            write_text_atomic(tmp_path / "elsewhere.csv", "no")
        with pytest.raises(mftire.errors.MftireInputError, match="is the input file"):
            write_text_atomic(inp, "no")
    assert (tmp_path / "out.csv").read_text() == "2" and inp.read_text() == "x"
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["anything.md", "in.csv", "out.csv", "rep"]
    write_text_atomic(tmp_path / "elsewhere.csv", "library")  # no command: the library replaces as asked
    assert (tmp_path / "elsewhere.csv").read_text() == "library"


# --------------------------------------------------------------------------- names from data

HOSTILE = ["x/../../../../elsewhere/PWNED_run", "/..", "..", ".", "", "/etc/passwd", "a\\b", "C:\\x", "\x00nul",
           "line\nbreak", "-rf", ".hidden", "résumé", "a" * 300, "$x^2$", "a b", "%2e%2e%2f", "~/x", "a/./b",
           "temp [°C]", "con", "....//....//x"]


@pytest.mark.parametrize("label", HOSTILE)
def test_names_a_label_from_data_is_a_safe_file_name(label):
    import re

    from mftire.iotools.output import safe_name

    name = safe_name(label)
    assert re.fullmatch(r"[A-Za-z0-9._-]+", name) and ".." not in name, name
    assert not name.startswith((".", "-")) and len(name) <= 70
    assert os.path.basename(name) == name and name not in (".", "..")


def test_names_are_unique_within_a_command():
    from mftire.iotools.output import command_scope, safe_name

    with command_scope():
        names = [safe_name(x) for x in ("a/b", "a_b", "a?b", "Fz", "fz", "a/b")]
    assert names[0] == names[5]  # the same label, the same name
    assert len({n.lower() for n in names[:5]}) == 5  # distinct labels never share a name (any letter case)


def test_names_hostile_columns_stay_inside_the_diagnosis_folder(run):
    df = pd.read_csv(run.p("sweeps.csv"))
    z = np.linspace(-1.0, 1.0, len(df))
    df["x/../../../../elsewhere/PWNED_temp"] = z  # explains the Fy residual: plotted
    df["Fy"] = df["Fy"] * (1.0 + 0.1 * z)
    df["/.."] = np.cos(7.0 * z)
    df["$bad"] = np.sin(3.0 * z)
    df.to_csv(run.p("hostile.csv"), index=False)
    out = run.root / "a" / "b" / "diag"
    run(["diagnose", run.p("hostile.csv"), "--tir", run.p("tyre.tir"), "--output", str(out), "--permutations", "9"],
        0, created=set())
    written = {str(p.relative_to(run.root)) for p in run.root.rglob("*") if p.is_file()}
    outside = {w for w in written if not w.startswith("a/b/diag/")} - {"tyre.tir", "points.csv", "sweeps.csv",
                                                                        "fe_braking.csv", "run.dat", "hostile.csv"}
    assert outside == set()
    assert all(p.parent == out for p in run.root.parent.rglob("*PWNED*"))  # nothing above the output folder
    assert any(p.name.startswith("residual_vs_x_elsewhere_PWNED_temp") for p in out.iterdir())


def test_names_figures_of_hostile_labels_do_not_crash(tmp_path):
    from types import SimpleNamespace

    from mftire.diagnosis.report import _figures
    from mftire.iotools.output import command_scope

    x = np.linspace(0.0, 1.0, 50)
    labels = ["/..", "$x^", "a/../../b", "x" * 200]
    df = pd.DataFrame({**{lab: x * (i + 1) for i, lab in enumerate(labels)}, "residual_Fy": np.sin(5 * x)})
    ranking = [SimpleNamespace(variable=lab, channel="Fy", score=0.5, significant=True) for lab in labels]
    result = SimpleNamespace(data=df, ranking=ranking, effect=None, train=None)
    out = tmp_path / "d"
    with command_scope():
        OutputPlan((), False).folder(out)
        _figures(result, str(out))
    assert sorted(p.name for p in tmp_path.rglob("*"))[0] == "d" and len(list(out.iterdir())) == 4
    assert all(p.parent == out for p in tmp_path.rglob("*.png"))


# --------------------------------------------------------------------------- .tir: one parameter check

VALUE_ERRORS = {  # values that made a channel NaN or absurd, and the message
    "NOMPRES=0": ({"NOMPRES": 0.0}, "NOMPRES = 0 must be > 0"),
    "NOMPRES<0": ({"NOMPRES": -2e5}, "NOMPRES = -200000 must be > 0"),
    "LFZO=0": ({"LFZO": 0.0}, "LFZO = 0 must be >= 0.001"),
    "LONGVL=0": ({"LONGVL": 0.0}, "LONGVL = 0 must be > 0"),
    "VXLOW=0": ({"VXLOW": 0.0}, "VXLOW = 0 must be > 0"),
    "LMUX<0": ({"LMUX": -1.0}, "LMUX = -1 must be >= 0"),
    "ALPMIN>ALPMAX": ({"ALPMIN": 0.5, "ALPMAX": -0.5}, "ALPMIN = 0.5 rad is not below ALPMAX = -0.5 rad"),
    "PRESMIN>PRESMAX": ({"PRESMIN": 4e5, "PRESMAX": 2e5}, "PRESMIN = 400000 Pa is not below PRESMAX"),
    "KPUMIN>KPUMAX": ({"KPUMIN": 1.0, "KPUMAX": -1.0}, "KPUMIN = 1 is not below KPUMAX = -1"),
    "CAMMIN>CAMMAX": ({"CAMMIN": 0.1, "CAMMAX": -0.1}, "CAMMIN = 0.1 rad is not below CAMMAX"),
    "FZMIN>FZMAX": ({"FZMIN": 9000.0, "FZMAX": 100.0}, "FZMIN = 9000 N is not below FZMAX = 100 N"),
    "LFZO=1e-9": ({"LFZO": 1e-9}, "LFZO = 1e-09 must be >= 0.001"),
    "FNOMIN=1e-3": ({"FNOMIN": 1e-3}, "FNOMIN = 0.001 must be >= 1"),
    "PKX2=1e308": ({"PKX2": 1e308}, "PKX2 = 1e+308: beyond any Magic Formula coefficient"),
    "RHY2=-1e308": ({"RHY2": -1e308}, "RHY2 = -1e+308: beyond any Magic Formula coefficient"),
    "mu=1e6": ({"PDX1": 1e6}, "peak friction of Fx 1e+06"),
    "muy=-50": ({"PDY1": -50.0}, "peak friction of Fy"),
    "extension=1e300": (None, "EXT1_C1 = 1e+300 is absurd"),
}


def _bad_tir(r: Run, case: str) -> str:
    values, _ = VALUE_ERRORS[case]
    if values is None:
        from test_fmu_guards import extension_entries

        entries = {**extension_entries(["Vs"]), "EXT1_C1": 1e300}
        return str(_tir_with(Path(r.p("tyre.tir")), entries, section="MFTIRE_EXTENSIONS"))
    return str(_tir_with(Path(r.p("tyre.tir")), values))


@pytest.mark.parametrize("case", sorted(VALUE_ERRORS))
@pytest.mark.parametrize("cmd", ["info", "evaluate"])
def test_tir_constants_that_break_a_channel_are_errors(run, cmd, case):
    _bad_tir(run, case)
    msg = VALUE_ERRORS[case][1]
    if cmd == "info":
        run.capsys.readouterr()
        assert main(["info", run.p("tyre.tir")]) == 2
        out = run.capsys.readouterr().out
        assert any(ln.startswith("  error: ") and msg in ln for ln in out.splitlines()) and "np.float64" not in out
    else:
        run(_commands(run, run.p("o.csv"))["evaluate"], 2, run.p("tyre.tir"), msg)


@pytest.mark.parametrize("case", ["NOMPRES=0", "LFZO=0", "KPUMIN>KPUMAX"])
def test_tir_fit_refuses_a_broken_template(run, case):
    _bad_tir(run, case)
    run(_commands(run, run.p("f.tir"))["fit"], 2, VALUE_ERRORS[case][1])


@pytest.mark.parametrize("key,value,text", [("LMUX", 0.0, "LMUX = 0: Fx is identically zero"),
                                            ("LMUY", 0.0, "LMUY = 0: Fy is identically zero"),
                                            ("TYRESIDE", "MIDDLE", "TYRESIDE = 'MIDDLE' is not one of")])
def test_tir_suspicious_values_warn_and_fail_info_strict(run, key, value, text):
    _tir_with(Path(run.p("tyre.tir")), {key: value})
    run.capsys.readouterr()
    assert main(["info", run.p("tyre.tir")]) == 0
    assert f"warning: {text}" in run.capsys.readouterr().out
    assert main(["info", run.p("tyre.tir"), "--strict"]) == 1
    with pytest.warns(MftireTirWarning, match=text.split(":")[0]):
        mftire.load(run.p("tyre.tir"))


def test_tir_unknown_format_name_warns_and_strict_refuses(run):
    _tir_with(Path(run.p("tyre.tir")), {"PROPERTY_FILE_FORMAT": "FOO"})
    with pytest.warns(Warning, match="PROPERTY_FILE_FORMAT = 'FOO' is not a format mftire knows"):
        mftire.load(run.p("tyre.tir"))
    err = run(["info", run.p("tyre.tir")], 0)
    assert "warning: " in err and "'FOO' is not a format mftire knows" in err
    run(["info", run.p("tyre.tir"), "--strict"], 2, "'FOO' is not a format mftire knows", "strict reading")


def test_tir_misspelled_key_did_you_mean(run):
    text = MF61.read_text()
    lines = [("LMUXX" + ln[4:]) if ln.split("=")[0].strip() == "LMUX" else ln for ln in text.splitlines(True)]
    Path(run.p("tyre.tir")).write_text("".join(lines))
    with pytest.warns(Warning, match="LMUXX in \\[SCALING_COEFFICIENTS\\] is not a key mftire knows: did you mean "
                      "LMUX\\? \\(LMUXX is ignored; LMUX takes its default\\)"):
        mftire.load(run.p("tyre.tir"))
    err = run(["info", run.p("tyre.tir"), "--strict"], 2, "did you mean LMUX?", "strict reading")
    assert "line " in err
    err = run(_commands(run, run.p("o.csv"))["evaluate"] + ["--strict"], 2, "did you mean LMUX?")


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be"])
def test_tir_utf16_files_are_read(run, encoding):
    Path(run.p("tyre.tir")).write_bytes(MF61.read_text().encode(encoding))
    run.capsys.readouterr()
    assert main(["info", run.p("tyre.tir"), "--strict"]) == 0
    assert "checks:\n  all passed" in run.capsys.readouterr().out
    assert read_tir(run.p("tyre.tir")).flat()["PKY1"] == read_tir(MF61).flat()["PKY1"]


def test_tir_binary_file_is_named_as_such(run):
    Path(run.p("tyre.tir")).write_bytes(bytes(range(256)) * 8)
    run(["info", run.p("tyre.tir")], 2, "binary data (control characters): not a text .tir file")


def test_tir_limits_table_names_known_keys():
    from mftire.iotools.tir_checks import PARAMETER_LIMITS, RANGE_PAIRS
    from mftire.parameters import BY_KEY
    from mftire.transient import DEFAULT_CONSTANTS

    keys = [lim.key for lim in PARAMETER_LIMITS] + [k for pair in RANGE_PAIRS for k in pair[:2]]
    assert all(k in BY_KEY or k in DEFAULT_CONSTANTS for k in keys)  # .tir keys and the transient constants
    flat = {**with_defaults_of(MF61), **DEFAULT_CONSTANTS}
    assert all(lim.holds(flat[lim.key]) for lim in PARAMETER_LIMITS)  # the defaults and MF61 pass
    from mftire.parameters import parameter_bounds

    assert ("NOMPRES", "> 0") in parameter_bounds() and ("LFZO", ">= 0.001") in parameter_bounds()  # the FMU's form


def with_defaults_of(path: Path) -> dict:
    from mftire.parameters import with_defaults

    return with_defaults(read_tir(path))


# --------------------------------------------------------------------------- data: CSV inputs of the commands


def _csv(r: Run, name: str, text: str) -> str:
    Path(r.p(name)).write_text(text)
    return r.p(name)


def _evaluate(r: Run, name: str, *extra: str) -> list[str]:
    return ["evaluate", r.p("tyre.tir"), "--input", r.p(name), "--output", r.p("o.csv"), *extra]


WARNED_INPUTS = {  # CSV, mode, the one-line warning
    "sae-Fz": ("Fz,kappa,alpha,gamma\n-4000,0,0.05,0\n-6000,-0.1,0,0\n", "111", "every vertical load Fz is negative"),
    "gamma-deg-211": ("Fz,kappa,alpha,gamma\n4000,0,0.05,3\n4000,0,0.05,-4\n", "211", "gamma is in radians"),
    "gamma-deg-111": ("Fz,kappa,alpha,gamma\n4000,0,0.05,3\n4000,0,0.05,-4\n", "111", "gamma is in radians"),
    "P-psi-211": ("Fz,kappa,alpha,gamma,P\n4000,-0.1,0,0,32\n", "211", "the values look like psi"),
    "P-kPa-111": ("Fz,kappa,alpha,gamma,P\n4000,-0.1,0,0,220\n", "111", "the values look like kPa"),
    "P-bar-211": ("Fz,kappa,alpha,gamma,P\n4000,-0.1,0,0,2.2\n", "211", "the values look like bar"),
    "Vx-huge": ("Fz,kappa,alpha,gamma,Vx\n4000,0,0.05,0,1e308\n", "111", "Vx is in m/s"),
    "alpha-deg-211": ("Fz,kappa,alpha,gamma\n4000,0,5,0\n", "211", "alpha is in radians"),
    "alpha-1e308": ("Fz,kappa,alpha,gamma\n4000,0,1e308,0\n", "111", "beyond any angle"),  # no numpy overflow
}


@pytest.mark.parametrize("case", sorted(WARNED_INPUTS))
def test_data_unit_and_sign_slips_warn_in_every_mode(run, case):
    text, mode, warning = WARNED_INPUTS[case]
    _csv(run, "in.csv", text)
    err = run(_evaluate(run, "in.csv", "--mode", mode), 0, created={"o.csv"})
    lines = err.strip().splitlines()
    assert any(warning in ln for ln in lines), err
    assert all(ln.startswith("mftire evaluate: warning: ") for ln in lines), err  # one line each, ours only
    assert "overflow encountered" not in err and "np.float64" not in err
    out = pd.read_csv(run.p("o.csv"))
    if case in ("Vx-huge", "alpha-1e308"):
        return
    assert np.isfinite(out[["Fx", "Fy", "Mz"]].to_numpy()).all()


def test_data_evaluate_never_writes_two_columns_of_one_name(run):
    _csv(run, "in.csv", "Fz,kappa,alpha,gamma,Fx,Fx_model,Fx_model_2\n4000,-0.1,0,0,1,2,3\n")
    run(_evaluate(run, "in.csv"), 0, created={"o.csv"})
    header = Path(run.p("o.csv")).read_text().splitlines()[0].split(",")
    assert len(header) == len(set(header)) and "Fx_model_3" in header
    out = pd.read_csv(run.p("o.csv"))
    assert out["Fx_model"].tolist() == [2] and out["Fx_model_2"].tolist() == [3]  # the user's values, by name


@pytest.mark.parametrize("header,hint", [("fz,kappa,alpha,gamma", "column 'fz' looks like Fz"),
                                         ("Fz,Kappa,alpha,gamma", "column 'Kappa' looks like kappa"),
                                         ("Fz,kappa,SA,gamma", "column 'SA' looks like alpha in 'deg'")])
def test_data_evaluate_names_the_rename(run, header, hint):
    _csv(run, "in.csv", header + "\n4000,0,0.05,0\n")
    run(_evaluate(run, "in.csv"), 2, "missing column(s)", hint, "rename")


def test_data_infinite_cell_is_named_without_numpy_repr(run):
    _csv(run, "in.csv", "Fz,kappa,alpha,gamma\n4000,inf,0.05,0\n")
    run(_evaluate(run, "in.csv"), 2, "column 'kappa', row 1 (line 2): inf is not a finite number")


def test_data_fit_on_a_few_rows_is_an_error_naming_the_minimum(run):
    pd.read_csv(run.p("sweeps.csv")).head(5).to_csv(run.p("few.csv"), index=False)
    argv = ["fit", run.p("few.csv"), "--template", run.p("tyre.tir"), "--output", run.p("f.tir")]
    run(argv, 2, "too few for the stages asked for", "needed", "nothing fitted")


@pytest.mark.parametrize("weight", ["0", "-1", "inf", "nan", "x"])
def test_data_fit_weights_must_be_finite_and_positive(run, weight):
    argv = _commands(run, run.p("f.tir"))["fit"] + ["--weights", f"sweeps={weight}"]
    run(argv, 2, "--weights: weight of 'sweeps'")


def test_data_fit_weight_of_one_source_has_no_effect(run):
    base = _commands(run, run.p("a.tir"))["fit"] + ["--stages", "1,2"]
    run(base, 0, created={"a.tir"})
    heavy = _commands(run, run.p("b.tir"))["fit"] + ["--stages", "1,2", "--weights", "sweeps=1e308"]
    run(heavy, 0, created={"b.tir"})
    assert read_tir(run.p("a.tir")).flat() == read_tir(run.p("b.tir")).flat()


# --------------------------------------------------------------------------- api: odd inputs of Tyre.evaluate


@pytest.fixture(scope="module")
def mf61():
    return mftire.load(MF61)


API_REFUSED = {
    "None": ({"Fz": None}, TypeError, "Fz is None"),
    "gamma None": ({"gamma": None}, TypeError, "gamma is None"),
    "bool": ({"Fz": True}, TypeError, "Fz = True is a boolean"),
    "numpy bool": ({"kappa": np.bool_(False)}, TypeError, "is a boolean"),
    "bool array": ({"alpha": np.array([True, False])}, TypeError, "alpha holds booleans"),
    "datetime64": ({"Fz": np.datetime64("2020-01-01")}, TypeError, "holds dates or times"),
    "datetime64 array": ({"Vx": np.array(["2020-01-01"], dtype="datetime64[D]")}, TypeError, "dates or times"),
    "timedelta": ({"P": np.timedelta64(3, "s")}, TypeError, "dates or times"),
    "python datetime": ({"Fz": __import__("datetime").datetime(2020, 1, 1)}, TypeError, "dates or times"),
    "list with None": ({"Fz": [4000.0, None]}, TypeError, "NoneType values"),
    "complex": ({"Fz": 4000.0 + 1j}, TypeError, "is a complex number"),
    "complex array": ({"kappa": np.array([0.1 + 0j])}, TypeError, "holds complex numbers"),
    "ragged": ({"alpha": [[0.1], [0.1, 0.2]]}, ValueError, "ragged sequence"),
    "masked": ({"Fz": np.ma.masked_array([4000.0, 5000.0], [False, True])}, ValueError, "1 masked point"),
    "misaligned": ({"Fz": pd.Series([4000.0, 5000.0], index=[0, 1]), "kappa": pd.Series([0.0, -0.1], index=[1, 2])},
                   ValueError, "different indexes"),
}


@pytest.mark.parametrize("case", sorted(API_REFUSED))
def test_api_odd_inputs_are_refused(mf61, case):
    kw, exc, text = API_REFUSED[case]
    args = {"Fz": 4000.0, "kappa": -0.05, "alpha": 0.02, **kw}
    with pytest.raises(exc, match=text):
        mf61.evaluate(**args)


def test_api_plain_masked_and_aligned_inputs_are_taken(mf61):
    ref = mf61.evaluate(np.array([4000.0, 5000.0]), np.array([0.0, -0.1]), 0.02)
    out = mf61.evaluate(np.ma.masked_array([4000.0, 5000.0], [False, False]), np.array([0.0, -0.1]), 0.02)
    np.testing.assert_array_equal(out["Fx"], ref["Fx"])
    idx = [7, 9]
    out = mf61.evaluate(pd.Series([4000.0, 5000.0], index=idx), pd.Series([0.0, -0.1], index=idx), 0.02)
    np.testing.assert_array_equal(out["Fx"], ref["Fx"])


@pytest.mark.parametrize("mode", [111, 211])
@pytest.mark.parametrize("name", ["Fz", "kappa", "alpha", "gamma", "Vx", "P"])
def test_api_infinite_inputs_are_treated_as_nan(mf61, name, mode):
    base = {"Fz": np.array([4000.0, 5000.0]), "kappa": np.array([-0.05, 0.0]), "alpha": np.array([0.02, 0.03]),
            "gamma": np.zeros(2), "Vx": np.full(2, 15.0), "P": np.full(2, 2.4e5)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for backend in ("kernel", "numpy") if mftire.mf.kernel.load() is not None else ("numpy",):
            res = []
            for bad in (np.inf, np.nan):
                kw = {**base, name: np.array([base[name][0], bad])}
                res.append(mf61.evaluate(**kw, mode=mode, backend=backend))
            for k in ("Fx", "Fy", "Mz", "Mx", "My", "Re"):
                assert np.isfinite(res[0][k]).all(), (backend, k)
                np.testing.assert_array_equal(res[0][k], res[1][k])  # inf gives what NaN gives


@pytest.mark.parametrize("mode", [112, 122, 212, 222])
def test_api_turn_slip_at_standstill_takes_its_limit(mode):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label in ("MF61", "MF62", "MF52"):
            tyre = mftire.load(REFERENCE_TYRES[label])
            for backend in ("kernel", "numpy") if mftire.mf.kernel.load() is not None else ("numpy",):
                out = tyre.evaluate(np.array([4000.0, 3000.0]), np.array([0.0, -0.1]), 0.05, 0.0, 0.1, Vx=0.0,
                                    mode=mode, backend=backend)
                for k in ("Fy", "Mz", "Mx", "Fx", "My"):
                    assert np.isfinite(out[k]).all(), (label, backend, k)
                ahead, back = (tyre.evaluate(np.array([4000.0, 3000.0]), np.array([0.0, -0.1]), 0.05, 0.0, 0.1,
                                             Vx=v, mode=mode, backend=backend)["Fy"] for v in (1e-9, -1e-9))
                if mode < 200:  # the low-speed reduction makes the spin vanish: continuous through Vx = 0
                    np.testing.assert_allclose(out["Fy"], ahead, atol=1e-3)
                elif mode == 212:  # without limits the spin shift changes sign with Vx (eq 4.86): at 0 it lies between
                    assert np.all((np.minimum(ahead, back) - 1e-9 <= out["Fy"]) & (out["Fy"] <= np.maximum(ahead, back)
                                                                                + 1e-9))


@pytest.mark.parametrize("kw,text", [({"gamma": 4.0}, "gamma is in radians"), ({"P": 30.0}, "look like psi"),
                                     ({"Fz": np.array([-4000.0, -6000.0])}, "negative or zero"),
                                     ({"Vx": 1e308}, "Vx is in m/s")])
@pytest.mark.parametrize("mode", [111, 211])
def test_api_unit_warnings_in_every_mode(kw, text, mode):
    tyre = mftire.load(MF61)
    args = {"Fz": 4000.0, "kappa": -0.05, "alpha": 0.02, **kw}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tyre.evaluate(**args, mode=mode)
    assert any(issubclass(w.category, MftireUnitWarning) and text in str(w.message) for w in caught)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]  # no numpy overflow leaks


def test_api_tyre_from_a_mapping_takes_the_one_parameter_check():
    flat = read_tir(MF61).flat()
    for key, value, text in (("NOMPRES", 0.0, "NOMPRES = 0 must be > 0"), ("LFZO", 0.0, "LFZO = 0"),
                             ("ALPMIN", 2.0, "ALPMIN = 2 rad is not below ALPMAX")):
        with pytest.raises(TirCheckError, match=text):
            mftire.Tyre({**flat, key: value})
    from mftire.fitting import fit_tir

    with pytest.raises(TirCheckError, match="LONGVL = 0"):
        fit_tir(pd.DataFrame({"Fz": [4000.0]}), {**flat, "LONGVL": 0.0})


def test_api_evaluate_frame_names_the_rename(mf61):
    with pytest.raises(mftire.errors.MftireInputError, match="column 'Fz_kN' looks like Fz in 'kN'"):
        mf61.evaluate_frame(pd.DataFrame({"Fz_kN": [4.0], "kappa": [0.0], "alpha": [0.0]}))


# --------------------------------------------------------------------------- fmu: export refuses what the FMU would


@pytest.mark.parametrize("case", sorted(VALUE_ERRORS))
def test_fmu_export_refuses_constants_that_break_a_channel(run, case):
    _bad_tir(run, case)
    run(_commands(run, run.p("t.fmu"))["export-fmu"], 2, VALUE_ERRORS[case][1])


@pytest.mark.parametrize("ident", ["tyre\n", "ty re", "1tyre", "tyre;"])
def test_fmu_model_identifier_must_be_a_whole_c_identifier(run, ident):
    from mftire.fmu.build import FMUExportError
    from mftire.fmu.export import export_fmu

    try:
        from mftire.fmu.build import find_compiler

        find_compiler()
    except FMUExportError:
        pytest.skip("no C compiler")
    with pytest.raises(FMUExportError, match="is not a C identifier"):
        export_fmu(MF61, run.p("t.fmu"), model_identifier=ident)
    assert not Path(run.p("t.fmu")).exists()


def test_fmu_export_of_a_mapping_takes_the_check(run):
    from mftire.fmu.build import FMUExportError
    from mftire.fmu.export import export_fmu

    with pytest.raises(FMUExportError, match="NOMPRES = 0 must be > 0"):
        export_fmu({**read_tir(MF61).flat(), "NOMPRES": 0.0}, run.p("t.fmu"))
    assert not Path(run.p("t.fmu")).exists()


# --------------------------------------------------------------------------- processes: signals to the parent


def _descendants(pid: int) -> list[tuple[int, str]]:
    """(pid, command name) of every live process below ``pid`` (Linux /proc)."""
    children: dict[int, list[tuple[int, str]]] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            text = Path(f"/proc/{d}/stat").read_text()
        except OSError:
            continue
        rest = text[text.rindex(")") + 2:].split()
        if rest[0] != "Z":
            children.setdefault(int(rest[1]), []).append((int(d), text[text.index("(") + 1:text.rindex(")")]))
    out, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.append(child)
            todo.append(child[0])
    return out


def _alive(pid: int) -> bool:
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return text[text.rindex(")") + 2] != "Z"


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux /proc")
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT"])
@pytest.mark.parametrize("cmd", ["demo", "export-fmu"])
def test_fmu_and_demo_signal_to_the_parent_stops_everything_within_3_s(tmp_path, cmd, sig):
    """SIGTERM or SIGINT to the parent alone, while workers (demo) or the C compiler (export-fmu) run:
    the parent exits within 3 s, no worker or compiler is left, no temporary or build folder stays."""
    import signal
    import subprocess
    import sys
    import time

    if cmd == "export-fmu":
        from conftest import have_c_compiler

        if not have_c_compiler():
            pytest.skip("no C compiler")
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    out = tmp_path / ("demo" if cmd == "demo" else "t.fmu")
    argv = (["demo", "--quick", "--jobs", "2", "--output", str(out)] if cmd == "demo" else
            ["export-fmu", str(MF61), "--output", str(out)])
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1]), "TMPDIR": str(tmpdir)}
    # Ctrl-C's default disposition in the command, however the test run was started: a test run started in the
    # background of a non-interactive shell ignores SIGINT, the command would inherit that, and Python keeps an
    # inherited SIG_IGN (as it should: nohup and background jobs ask for it)
    proc = subprocess.Popen([sys.executable, "-m", "mftire.cli", *argv], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # fmt: skip
    try:
        wanted = ("python",) if cmd == "demo" else ("cc", "gcc", "clang", "cc1", "as", "collect2", "ld")
        start, running = time.monotonic(), []
        while time.monotonic() - start < 120 and proc.poll() is None:
            running = _descendants(proc.pid)  # the snapshot that saw them: a compiler may end before a second look
            if any(name.startswith(wanted) for _, name in running):
                break
            time.sleep(0.01)
        assert proc.poll() is None, "the command ended before the signal"
        if cmd == "demo":
            time.sleep(0.3)
            running = sorted(set(running) | set(_descendants(proc.pid)))
        assert running
        t0 = time.monotonic()
        os.kill(proc.pid, getattr(signal, sig))
        proc.wait(10)
        elapsed = time.monotonic() - t0
        err = proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
    assert elapsed < 3.0, elapsed
    assert proc.returncode == (143 if sig == "SIGTERM" else 130), err
    assert err.strip().splitlines()[-1] == f"mftire {cmd}: {'terminated' if sig == 'SIGTERM' else 'interrupted'}"
    deadline = time.monotonic() + 3.0 - elapsed
    while time.monotonic() < deadline and any(_alive(p) for p, _ in running):
        time.sleep(0.05)
    assert not [(p, n) for p, n in running if _alive(p)]  # no worker, no compiler left
    assert list(tmpdir.iterdir()) == []  # no mftire-fmu-* build folder, no compiler temporaries
    if cmd == "export-fmu":
        assert not out.exists()
    else:
        assert not [p for p in out.rglob("*") if p.name.endswith(".tmp") or p.name.startswith(".")]


@pytest.mark.parametrize("column", ["Fy", "Mz"])
def test_data_fit_refuses_sae_signed_forces(run, column):
    df = pd.read_csv(run.p("sweeps.csv"))
    df[column] = -df[column]
    df.to_csv(run.p("sae.csv"), index=False)
    argv = ["fit", run.p("sae.csv"), "--template", run.p("tyre.tir"), "--output", run.p("f.tir")]
    run(argv, 2, f"column '{column}'", "has the wrong sign", "SAE-signed data?")


def test_tir_mutated_constants_are_refused_or_evaluate_finite(tmp_path):
    """150 files with one to three values of the evaluator's keys set to adversarial numbers (fixed
    seed): each is refused with one line naming the file, or it evaluates to finite forces and moments."""
    import random

    from mftire.iotools.evaluator_keys import evaluator_keys
    from mftire.iotools.tir import write_tir
    from mftire.parameters import BY_KEY

    keys = sorted(k for k in evaluator_keys() if k != "FITTYP" and k in BY_KEY and BY_KEY[k].unit != "str")
    values = [0.0, -1.0, 1e308, -1e308, 1e-320, 1e6, -1e6, 1e3, -1e3, 1e-9, 5.0, -5.0, 1e5, 9e99]
    rng = random.Random(24)
    bases = [read_tir(REFERENCE_TYRES[label]) for label in ("MF61", "MF52", "MF62")]
    refused = 0
    for i in range(150):
        params = rng.choice(bases).copy()
        for _ in range(rng.randint(1, 3)):
            params.set(rng.choice(keys), rng.choice(values))
        path = tmp_path / f"m{i}.tir"
        write_tir(params, path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                tyre = mftire.load(path)
            except mftire.errors.MftireError as exc:
                refused += 1
                assert str(path) in str(exc) and "\n" not in str(exc) and "np.float64" not in str(exc)
                continue
            with np.errstate(all="raise"):  # no numpy floating-point warning may leak either
                out = tyre.evaluate(np.array([2000.0, 4000.0, 8000.0]), np.array([-0.1, 0.0, 0.05]),
                                    np.array([0.02, -0.1, 0.0]), gamma=0.02)
        bad = [c for c in ("Fx", "Fy", "Mz", "Mx", "My") if not np.isfinite(out[c]).all()]
        assert not bad, (path.name, bad, [ln for ln in path.read_text().splitlines() if "1e" in ln][:5])
    assert 20 < refused < 130  # both outcomes are exercised
