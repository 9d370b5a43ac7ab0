"""The command line keeps its promise: results on stdout, or one line on stderr and status 2."""

from __future__ import annotations

import subprocess
import sys

import pytest

from kinengine.cli import main


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["verify", "abb_irb120", "--samples", "-3"],
            "argument --samples: expected a whole number in [1, 100000], got -3",
        ),
        (
            ["verify", "abb_irb120", "--samples", "0"],
            "argument --samples: expected a whole number in [1, 100000], got 0",
        ),
        (["verify", "abb_irb120", "--json", "/nonexistent/x.json"], "folder '/nonexistent' does not exist"),
        (
            ["bench", "abb_irb120", "--quick", "--json", "/nonexistent/b.json"],
            "folder '/nonexistent' does not exist",
        ),
        (["bench", "abb_irb120", "--quick", "--plot", "."], "'.' is a folder"),
    ],
)
def test_bad_option_values_stop_before_any_work(capsys, argv, message):
    with pytest.raises(SystemExit) as info:
        main(argv)
    captured = capsys.readouterr()
    assert info.value.code == 2 and captured.out == ""
    assert message in captured.err


def test_pose_prints_nothing_before_an_error(capsys):
    assert main(["pose", "abb_irb120", "--rotation", "euler_zyx"]) == 2  # ZYX gimbal lock at home
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()  # the gimbal-lock warning is dropped: the error says it (issue 25)
    assert len(lines) == 1, lines
    assert lines[0].startswith("kinengine: error: 'euler_zyx' is at a representation singularity")


def test_pose_names_only_the_parameterizations_asked_for(capsys):
    assert main(["pose", "scara", "--position", "cylindrical"]) == 0
    out = capsys.readouterr().out
    assert "chi (cylindrical) = rho 0.60000, theta 0.00000, z 0.35000" in out  # l1 + l2 = 0.6 m, h0 - d
    assert "None" not in out


@pytest.mark.slow
def test_a_reader_that_leaves_early_is_not_an_error():
    code = "import sys; from kinengine.cli import main; sys.exit(main(sys.argv[1:]))"
    run = subprocess.run(
        f"{sys.executable} -c '{code}' pose abb_irb120 | head -1",
        shell=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.stdout == "robot abb_irb120 (6 dof), frame 'tool0'\n"
    assert "Traceback" not in run.stderr and "BrokenPipe" not in run.stderr


def test_unknown_reference_is_an_option_error_and_a_value_error(abb):
    import kinengine

    with pytest.raises(kinengine.OptionError, match="unknown reference 'global'") as info:
        abb.jacobian(abb.neutral(), "tool0", reference="global")
    assert isinstance(info.value, ValueError)


def test_info_lists_coordinates_types_limits_and_mimic_joints(capsys, tmp_path):
    from custom_robots import mixed_chain_urdf

    path = tmp_path / "mixed.urdf"
    path.write_text(mixed_chain_urdf())
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "root link (the frame poses are given in): base" in out
    assert out[4].split() == ["0", "shoulder", "revolute", "-2.5", "2.5", "2", "10"]  # + velocity, effort
    assert out[6].split() == ["2", "spin", "continuous", "-inf", "inf", "2", "10"]
    assert "  - finger_b_joint (mimic, revolute) = -1.5·finger_a_joint + 0.2" in out
