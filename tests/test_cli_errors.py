"""Issue 15, command line: every bad input is one line on stderr (``kinengine: error: ...``) and exit
status 2, nothing on stdout; outputs are checked before the work; names cannot break lines."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from kinengine import KinematicsError
from kinengine.cli import main
from kinengine.cli.arguments import one_line, printable

pytestmark = pytest.mark.slow  # the CLI in subprocesses

REPO = Path(__file__).resolve().parents[1]


def run_main(argv: list[str], capsys) -> tuple[int, str, str]:
    """(exit status, stdout, stderr) of ``kinengine argv`` run in this process."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def run_cli(
    argv: list[str], *, stdout=subprocess.PIPE, env: dict[str, str] | None = None, timeout: float = 120.0
) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "kinengine", *argv],
        cwd=REPO,
        stdout=stdout,
        stderr=subprocess.PIPE,
        text=True,
        timeout=timeout,
        env=None if env is None else {**os.environ, **env},
    )


def assert_one_error_line(code: int, out: str, err: str, fragment: str = "") -> None:
    assert code == 2, (code, err)
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("kinengine: error: "), err
    assert fragment in lines[0], lines[0]


@pytest.mark.parametrize(
    "argv, fragment",
    [
        ([], "the following arguments are required: COMMAND"),
        (["nope"], "invalid choice: 'nope'"),
        (["pose"], "the following arguments are required: robot"),
        (["pose", "abb_irb120", "--bogus"], "unrecognized arguments: --bogus"),
        (["pose", "abb_irb120", "--reference", "bad"], "argument --reference: invalid choice: 'bad'"),
        (["pose", "abb_irb120", "--q"], "argument --q: expected one argument"),
        (["pose", "abb_irb120", "--q", "1 5,0,0,0,0,0"], "entry 1 is '1 5'"),
        (["pose", "abb_irb120", "--q", "1_0,0,0,0,0,0"], "entry 1 is '1_0'"),
        (["pose", "abb_irb120", "--q", "\u0661,0,0,0,0,0"], "entry 1 is"),
        (["pose", "abb_irb120", "--q", "0,0,0,0,0,"], "entry 6 is an empty entry"),
        (["pose", "abb_irb120", "--frame", ""], "argument --frame: expected a name, got an empty string"),
        (
            ["show", "abb_irb120", "--dpi", "5000"],
            "argument --dpi: expected a whole number in [1, 600], got 5000",
        ),
        (["show", "abb_irb120", "--dpi", "0"], "argument --dpi"),
        (["show", "abb_irb120", "--dpi", "1_00"], "argument --dpi: expected a whole number, got '1_00'"),
        (["show", "abb_irb120", "-o", ""], "argument -o/--output: expected a file name, got an empty string"),
        (["show", "abb_irb120", "--ellipsoid", ""], "argument --ellipsoid: expected a name"),
        (
            ["verify", "abb_irb120", "--samples", "100000000"],
            "argument --samples: expected a whole number in [1, 100000]",
        ),
        (
            ["verify", "abb_irb120", "--samples", "1e3"],
            "argument --samples: expected a whole number, got '1e3'",
        ),
        (["verify", "abb_irb120", "--seed", "-1"], "argument --seed: expected a whole number in [0,"),
        (["verify", "abb_irb120", "--json", ""], "argument --json: expected a file name"),
        (
            ["verify", "abb_irb120", "--json", "/dev/full"],
            "argument --json: cannot write '/dev/full': not a regular file",
        ),
        (["verify", "abb_irb120", "--json", "/"], "argument --json: '/' is a folder"),
        (["verify", "abb_irb120", "--json", "/nonexistent/r.json"], "folder '/nonexistent' does not exist"),
        (
            ["bench", "abb_irb120", "--quick", "--json", "/dev/full"],
            "argument --json: cannot write '/dev/full'",
        ),
        (["show", "abb_irb120", "-o", "/dev/full"], "cannot write '/dev/full': not a regular file"),
        (["ik", "abb_irb120", "--xyz", "0.4,0,0.5", "--rpy", "0,1.2,inf"], "--rpy: expected three finite"),
        (
            ["ik", "abb_irb120", "--xyz", "0.4,nan,0.5"],
            "--xyz: expected three finite comma-separated numbers",
        ),
        (
            ["ik", "abb_irb120", "--xyz", "0.4,0,0.5", "--near", "0,0,0"],
            "--near: Expected `q` to have shape (6,)",
        ),
    ],
)
def test_bad_arguments_are_one_line_and_status_2(capsys, argv, fragment):
    assert_one_error_line(*run_main(argv, capsys), fragment)


def test_unwritable_outputs_are_refused_before_the_work(capsys, tmp_path):
    read_only = tmp_path / "ro.json"
    read_only.write_text("{}")
    read_only.chmod(0o444)
    dangling = tmp_path / "dangling.json"
    dangling.symlink_to(tmp_path / "missing" / "x.json")
    for path, fragment in (
        (read_only, "the file is read-only"),
        (dangling, "is a link to a missing file"),
        (tmp_path, "is a folder"),
    ):
        for argv in (["verify", "abb_irb120", "--json", str(path)], ["show", "abb_irb120", "-o", str(path)]):
            assert_one_error_line(*run_main(argv, capsys), fragment)
    if os.geteuid() != 0:  # root may write anywhere
        assert os.access(read_only, os.W_OK) is False


def test_kinengine_errors_are_one_line(capsys, tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="x"><link name="a"></robot>')
    assert_one_error_line(*run_main(["info", str(bad)], capsys), "not well-formed XML")
    assert_one_error_line(
        *run_main(["pose", "panda", "--frame", "panda_hnd"], capsys), "Did you mean 'panda_hand'"
    )
    assert_one_error_line(
        *run_main(["pose", "abb_irb120", "--q", "1e308,0,0,0,0,0"], capsys), "beyond ±1e+09"
    )
    assert_one_error_line(*run_main(["info", "a" * 300], capsys), "unknown robot")


def test_messages_are_collapsed_to_one_line_and_control_characters_escaped():
    assert one_line("line 1\n   line 2\r\nline 3") == "line 1 line 2 line 3"
    assert printable("a\nb\x1b[31m\u2028") == "a\\x0ab\\x1b[31m\\u2028"


def test_names_with_newlines_are_escaped_by_info(capsys, tmp_path):
    path = tmp_path / "nl.urdf"
    path.write_text(
        '<robot name="r&#10;x"><link name="a&#10;b"/><link name="c&#9;d"/>'
        '<joint name="j&#10;1" type="revolute"><parent link="a&#10;b"/><child link="c&#9;d"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    code, out, err = run_main(["info", str(path)], capsys)
    assert code == 0 and err == ""
    assert out.splitlines()[0].startswith("r\\x0ax: 1 dof")
    assert "frames: a\\x0ab, j\\x0a1, c\\x09d" in out
    assert len(out.splitlines()) == 7  # header 3, table 2, units, frames: no line broken by a name


def test_stdout_on_dev_full_is_one_line_and_status_2():
    with open("/dev/full", "w") as full:
        result = run_cli(["info", "abb_irb120"], stdout=full)
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        "kinengine: error: cannot write the output: No space left on device"
    ]


def test_non_ascii_names_print_under_an_ascii_locale(tmp_path):
    path = tmp_path / "bras.urdf"
    path.write_text('<robot name="bras_é"><link name="épaule"/></robot>', encoding="utf-8")
    result = run_cli(["info", str(path)], env={"PYTHONIOENCODING": "ascii"})
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0] == "bras_\\xe9: 0 dof, source " + str(path)
    failed = run_cli(["pose", str(path), "--frame", "épaul"], env={"PYTHONIOENCODING": "ascii"})
    assert failed.returncode == 2 and len(failed.stderr.splitlines()) == 1
    assert "\\xe9paule" in failed.stderr


@pytest.mark.parametrize("argv", [["show", "scara"], ["bench", "abb_irb120", "--quick", "--plot", "b.png"]])
def test_pictures_without_matplotlib_name_the_plot_extra(argv, capsys, monkeypatch, tmp_path):
    """matplotlib is the optional `plot` extra: without it (import fails) one line names the extra, and the
    benchmark says so before it runs."""
    monkeypatch.chdir(tmp_path)
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # `import matplotlib` raises ImportError
    assert_one_error_line(
        *run_main(argv, capsys),
        "pictures need matplotlib, which is not installed: pip install 'kinengine[plot]'",
    )
    assert not list(tmp_path.iterdir())


def test_robot_plot_without_matplotlib_names_the_plot_extra(abb, monkeypatch):
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(KinematicsError, match=r"pip install 'kinengine\[plot\]'"):
        abb.plot()
