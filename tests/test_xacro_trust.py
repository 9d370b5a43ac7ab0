"""The xacro trust boundary (issue 25): restricted evaluation by default, bounded expansion, files read.

Every file under tests/data/xacro/hostile and tests/data/xacro/trust was written for these tests. What
can hang or crash (huge powers, macro bombs, FIFOs) runs in a subprocess with a timeout. The allowed
constructs are checked against xacro's own evaluation (``trust_xacro=True``) of the same file.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import kinengine
from kinengine.errors import OptionError, ResourceLimitError, URDFError
from kinengine.urdf import Limits
from kinengine.urdf.packages import resolve_uri
from kinengine.urdf.xacro import expand_xacro

DATA = Path(__file__).parent / "data" / "xacro"
HOSTILE = DATA / "hostile"
TRUST = DATA / "trust"
PARTS = DATA / "elsewhere" / "parts_pkg"  # package kin_parts
REPO = Path(__file__).resolve().parents[1]
OPT_IN = "trust_xacro=True) (CLI: --trust-xacro)"


@pytest.fixture(autouse=True)
def no_ros_package_path(monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)


def run_python(code: str, timeout: float = 60.0, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``code`` in a fresh interpreter; TimeoutExpired (the test fails) if it hangs."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=cwd or REPO,
        env={k: v for k, v in os.environ.items() if k != "ROS_PACKAGE_PATH"},
    )


def write_xacro(folder: Path, body: str, name: str = "t.urdf.xacro") -> Path:
    path = folder / name
    path.write_text(
        '<?xml version="1.0"?>\n<robot name="t" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
        f'  <link name="base"/>\n{body}\n</robot>\n'
    )
    return path


# --- restricted evaluation ------------------------------------------------------------------------------


def test_allowed_constructs_expand_as_xacro_itself_expands_them():
    """Each allowed construct (yaml data, dotted yaml keys, math, args, displays, slices, comprehension,
    conditionals, $(eval ...)) gives the text xacro's own eval gives."""
    path = TRUST / "allowed_constructs.xacro"
    with pytest.warns(UserWarning, match="deprecated"):  # xacro's own eval warns on bare load_yaml/range
        trusted = expand_xacro(path, trust_xacro=True)
    safe = expand_xacro(path)
    assert safe == trusted
    assert 'effort="10"' in safe and 'name="tool_bLELE"' in safe  # 3 + 4 + 3 and the string expression
    robot = kinengine.load(path)
    assert robot.joint_names == ("j1", "j2")


def test_dunder_names_built_from_strings_do_not_run_a_command(tmp_path):
    """The walk type -> object.__subclasses__ -> os._wrap_close -> os.system, run with xacro's own eval,
    writes the marker file; the default evaluator refuses the file, naming file, line and the opt-in."""
    marker = tmp_path / "marker"
    path = HOSTILE / "dunder_from_strings.xacro"
    with pytest.raises(URDFError) as exc:
        kinengine.load(path, xacro_args={"marker": str(marker)})
    message = str(exc.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:") and OPT_IN in message
    assert "is not allowed by kinengine's safe xacro evaluator" in message
    assert not marker.exists()
    done = run_python(
        f"""
        from kinengine.urdf.xacro import expand_xacro
        expand_xacro({str(path)!r}, args={{"marker": {str(marker)!r}}}, trust_xacro=True)
        """
    )
    assert done.returncode == 0, done.stderr
    assert marker.exists()  # the file is a real attack: trusted mode is what the name says


@pytest.mark.parametrize(
    "expression, refused",
    [
        ("python.type(0)", "the name 'python'"),
        ("python.vars", "the name 'python'"),
        ("type(0)", "a call of type()"),
        ("vars()", "a call of vars()"),
        ("map(str, [1])", "a call of map()"),
        ("sorted([2, 1])", "a call of sorted()"),
        ("xacro.load_yaml.__globals__", "the attribute '__globals__'"),
        ("math.__dict__", "the attribute '__dict__'"),
        ("math.sys", "math.sys"),
        ("xacro.os", "xacro.os"),
        ("xacro.dotify.mro()", "the attribute .mro of a type"),
        ("(1).real", "the attribute .real of a int"),
        ("'a'.join(['b'])", "the attribute .join of a str"),
        ("'x'.format(1)", "the attribute .format of a str"),
        ("_x", "the name '_x'"),
        ("(lambda: 1)()", "a call of 'lambda: 1'"),
        ("f'x'", "JoinedStr"),
        ("'%999999999d' % 1", "'%' formatting of strings"),
        ("[x for x in range(10**9)]", "range of 1000000000 elements"),
        ("factorial(10**6)", "a call of factorial()"),
        ("2**5000", "more than 4096 bits"),
        ("9**9**9", "more than 4096 bits"),
        ("(2**4000) * (2**4000)", "an integer of more than 4096 bits"),
        ("1 &lt;&lt; 9999", "an integer of more than 4096 bits"),
        ("'x' * 10**9", "something that long"),
        ("str([['x' * 99999] * 9999])", "str() of a value of more than 1000000 characters"),
        ("[['x' * 99999] * 9999]", "a result of more than 1000000 characters"),
        ("round(1, 10**9)", "at most 400 digits"),
        ("(x := 1)", "NamedExpr"),
    ],
)
def test_expressions_outside_the_allow_list_are_refused(tmp_path, expression, refused):
    path = write_xacro(
        tmp_path, f'  <link name="l">\n    <visual><origin xyz="${{{expression}}}"/></visual></link>'
    )
    with pytest.raises(URDFError) as exc:
        expand_xacro(path)
    message = str(exc.value)
    assert "\n" not in message
    assert f"{path}:5: xacro expression " in message  # file and line
    assert expression.replace("&lt;", "<")[:40] in message and refused in message and OPT_IN in message


@pytest.mark.parametrize("expression", ["__import__('os')", "type(0)", "(1).real", "9**9**9"])
@pytest.mark.parametrize("spaces", ["", "  "])
def test_eval_substitutions_are_restricted_too(tmp_path, expression, spaces):
    """Refused like ${...}, naming file and line however the expression is spaced in the file."""
    path = write_xacro(tmp_path, f'  <link name="l"/>\n  <link name="$(eval {spaces}{expression}{spaces})"/>')
    with pytest.raises(URDFError) as exc:
        expand_xacro(path)
    assert (
        f"{path}:5: xacro expression " in str(exc.value)
        and "$(eval " in str(exc.value)
        and OPT_IN in str(exc.value)
    )


def test_properties_of_an_included_namespace_do_not_reach_xacros_globals(tmp_path):
    (tmp_path / "part.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:property name="w" value="0.5"/></robot>'
    )
    ok = write_xacro(tmp_path, '  <xacro:include filename="part.xacro" ns="p"/><link name="l${p.w * 2}"/>')
    assert '<link name="l1.0"/>' in expand_xacro(ok)
    bad = write_xacro(tmp_path, '  <xacro:include filename="part.xacro" ns="p"/><link name="${p.python}"/>')
    with pytest.raises(URDFError, match="undefined xacro property or name 'python'"):
        expand_xacro(bad)


def test_undefined_name_keeps_xacros_message(tmp_path):
    path = write_xacro(tmp_path, '  <link name="${nope}"/>')
    with pytest.raises(URDFError, match="undefined xacro property or name 'nope'"):
        expand_xacro(path)


def test_abs_and_tuple_are_allowed_in_the_safe_evaluator(tmp_path):
    """abs, tuple and set are on the issue's allow-list though xacro itself only has them as python.*."""
    path = write_xacro(tmp_path, '  <link name="l${abs(-2) + len(tuple([1, 2])) + len(set([1, 1]))}"/>')
    assert '<link name="l5"/>' in expand_xacro(path)


def test_trust_xacro_is_a_bool():
    with pytest.raises(OptionError, match="trust_xacro= takes True or False"):
        expand_xacro(TRUST / "allowed_constructs.xacro", trust_xacro="yes")  # type: ignore[arg-type]


# --- bounded expansion ------------------------------------------------------------------------------------


@pytest.mark.parametrize("trust", [False, True])
def test_macro_bomb_is_refused_by_the_macro_call_bound(trust):
    """2**40 links; the default Limits refuse it (a subprocess: without the bound it runs for days)."""
    done = run_python(
        f"""
        import kinengine
        try:
            kinengine.load({str(HOSTILE / "macro_bomb.xacro")!r}, trust_xacro={trust})
        except kinengine.errors.ResourceLimitError as exc:
            print(exc)
        """,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert f"more than Limits.max_macro_calls = {Limits().max_macro_calls} macro calls" in done.stdout


def test_huge_power_is_refused():
    done = run_python(
        f"""
        import kinengine
        try:
            kinengine.load({str(HOSTILE / "huge_power.xacro")!r})
        except kinengine.errors.URDFError as exc:
            print(exc)
        """
    )
    assert done.returncode == 0, done.stderr
    assert "9 ** 387420489 has more than 4096 bits is not allowed" in done.stdout


def test_expanded_text_bound(tmp_path):
    """Macro calls are charged the size of the body they copy: Limits.max_bytes bounds the output."""
    body = "".join(f'<link name="x{i}"/>' for i in range(50))
    path = write_xacro(
        tmp_path, f'<xacro:macro name="m">{body}</xacro:macro>' + "<xacro:m/>" * 10, name="big.urdf.xacro"
    )
    with pytest.raises(ResourceLimitError, match=r"writes more than Limits.max_bytes = 4000 bytes"):
        expand_xacro(path, limits=Limits(max_bytes=4000))


def test_wall_time_bound(tmp_path):
    calls = "".join(f'<xacro:m n="{i}"/>' for i in range(400))
    path = write_xacro(
        tmp_path, f'<xacro:macro name="m" params="n"><link name="l${{n}}"/></xacro:macro>{calls}'
    )
    with pytest.raises(ResourceLimitError, match=r"more than Limits.max_xacro_seconds = 0.001 s"):
        expand_xacro(path, limits=Limits(max_xacro_seconds=1e-3))
    assert "l399" in expand_xacro(path)


def test_limits_check_the_new_fields():
    with pytest.raises(OptionError, match="Limits.max_macro_calls must be a whole number"):
        Limits(max_macro_calls=0)
    with pytest.raises(OptionError, match="Limits.max_xacro_seconds must be a finite real number"):
        Limits(max_xacro_seconds=float("inf"))


# --- files read -------------------------------------------------------------------------------------------


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
@pytest.mark.parametrize("what", ["include", "yaml"])
@pytest.mark.parametrize("trust", [False, True])
def test_fifo_include_or_yaml_is_refused_without_blocking(tmp_path, what, trust):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    done = run_python(
        f"""
        import kinengine
        try:
            kinengine.load({str(HOSTILE / "include_fifo.xacro")!r}, trust_xacro={trust},
                           xacro_args={{"what": {what!r}, "path": {str(fifo)!r}}})
        except kinengine.errors.URDFError as exc:
            print(exc)
        """,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert f"{fifo}: not a regular file (a device, FIFO or socket)" in done.stdout


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_fifo_package_xml_on_ros_package_path_is_skipped(tmp_path):
    pkg = tmp_path / "ws" / "trap"
    pkg.mkdir(parents=True)
    os.mkfifo(pkg / "package.xml")
    done = run_python(
        f"""
        import os
        os.environ["ROS_PACKAGE_PATH"] = {str(tmp_path / "ws")!r}
        from kinengine.urdf.packages import resolve_package
        print(resolve_package("trap"))
        """,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(pkg)  # found by its folder name; the FIFO was not opened blocking


# --- package:// URIs stay inside their package --------------------------------------------------------


@pytest.mark.parametrize(
    "uri",
    [
        "package://kin_parts/../../../etc/passwd",
        "package://kin_parts/%2e%2e/%2E%2E/secret.stl",
        "package://kin_parts/meshes/../../x.stl",
    ],
)
def test_package_uri_cannot_leave_its_package(uri):
    with pytest.raises(URDFError) as exc:
        resolve_uri(uri, packages={"kin_parts": PARTS})
    assert f"{uri!r} leads out of the folder of its package" in str(exc.value)


def test_package_uri_symlink_out_of_the_package_is_refused(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "meshes").mkdir(parents=True)
    (tmp_path / "secret.stl").write_text("solid x\nendsolid x\n")
    (pkg / "meshes" / "link.stl").symlink_to(tmp_path / "secret.stl")
    (pkg / "meshes" / "inside.stl").symlink_to(pkg / "meshes" / "real.stl")
    with pytest.raises(URDFError, match="leads out of the folder of its package"):
        resolve_uri("package://pkg/meshes/link.stl", packages={"pkg": pkg})
    inside = resolve_uri("package://pkg/meshes/inside.stl", packages={"pkg": pkg})
    assert inside == (pkg / "meshes" / "real.stl").resolve()
    assert resolve_uri("package://pkg/meshes/./a/../b.stl", packages={"pkg": pkg}) == (
        pkg.resolve() / "meshes" / "b.stl"
    )


def test_viewer_scene_does_not_read_meshes_outside_the_package():
    """The viewer resolves meshes with resolve_uri: an escaping URI becomes a reason, not a file read."""
    pytest.importorskip("trimesh")
    from kinengine.presentation.viewer_scene import _load_mesh

    mesh, why = _load_mesh("package://kin_parts/../../../etc/passwd", None, None, {"kin_parts": PARTS})
    assert mesh is None and "leads out of the folder of its package" in why
    robot = kinengine.load(HOSTILE / "package_escape.urdf", packages={"kin_parts": PARTS})
    assert "tip" in robot.frame_names  # loading does not read meshes


# --- command line -----------------------------------------------------------------------------------------


def test_cli_trust_xacro_option(tmp_path):
    path = write_xacro(
        tmp_path,
        '  <link name="l${python.len([1, 2])}"/><joint name="j" type="fixed">'
        '<parent link="base"/><child link="l2"/></joint>',
    )
    base = [sys.executable, "-m", "kinengine", "info", str(path)]
    refused = subprocess.run(base, capture_output=True, text=True, timeout=120, cwd=REPO)
    assert refused.returncode != 0
    assert len(refused.stderr.splitlines()) == 1 and "--trust-xacro" in refused.stderr
    trusted = subprocess.run([*base, "--trust-xacro"], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert trusted.returncode == 0, trusted.stderr
    assert "l2" in trusted.stdout


def _trusted_refusal(name: str, limits: str) -> str:
    """The ResourceLimitError message of loading hostile file ``name`` trusted with ``Limits(limits)``, in
    a fresh interpreter."""
    done = run_python(
        f"""
        import kinengine
        from kinengine.urdf import Limits
        try:
            kinengine.load({str(HOSTILE / name)!r}, trust_xacro=True, limits=Limits({limits}))
        except kinengine.errors.ResourceLimitError as exc:
            print(exc)
        """,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_trusted_expression_that_does_not_finish_is_stopped_by_the_time_bound():
    """xacro's own eval of 9**9**9 runs for hours; the trusted expansion's child process is stopped."""
    message = _trusted_refusal("huge_power.xacro", "max_xacro_seconds=1")
    assert "the trusted xacro expansion takes more than Limits.max_xacro_seconds = 1 s" in message


def test_trusted_expansion_is_bounded_in_memory():
    """xacro's own eval of 'x' * 2**30 asks for 1 GiB; the child's address space is bounded by
    Limits.max_xacro_memory (RLIMIT_AS) and the expansion is refused, not run."""
    pytest.importorskip("resource")
    message = _trusted_refusal("huge_string.xacro", "max_xacro_memory=2**29")
    assert "needs more than Limits.max_xacro_memory = 536870912 bytes" in message


def test_max_xacro_memory_is_checked():
    with pytest.raises(OptionError, match="Limits.max_xacro_memory must be a whole number"):
        Limits(max_xacro_memory=1.5)
    with pytest.raises(OptionError, match="Limits.max_xacro_memory must be a whole number in"):
        Limits(max_xacro_memory=1024)


def test_trusted_expansion_reports_the_childs_errors_and_warnings(tmp_path):
    with pytest.raises(URDFError, match="missing xacro argument 'ur_type'"):
        expand_xacro(DATA / "errors" / "needs_arg.xacro", trust_xacro=True)
    with pytest.warns(UserWarning, match="unknown attribute"):
        text = expand_xacro(DATA / "errors" / "emits_warning.xacro", trust_xacro=True)
    with pytest.warns(UserWarning, match="unknown attribute"):
        assert text == expand_xacro(DATA / "errors" / "emits_warning.xacro")
