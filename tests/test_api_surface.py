"""Issue 16, items 1 and 7: types, small API points of the CLI, and what the install documentation promises."""

from __future__ import annotations

import inspect
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.cli import main

ROOT = Path(__file__).resolve().parents[1]
# absent when the tests run against an installed wheel (tests/ copied elsewhere): those tests skip
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text()) if (ROOT / "pyproject.toml").is_file() else None
needs_checkout = pytest.mark.skipif(PYPROJECT is None, reason="needs the source checkout (pyproject.toml, README)")


# ----------------------------------------------------------------------------------------------------------------------
# Item 7: types
# ----------------------------------------------------------------------------------------------------------------------


def test_package_is_marked_typed():
    assert (Path(cg.__file__).parent / "py.typed").is_file()  # also in an installed wheel
    if PYPROJECT is not None:
        assert "py.typed" in PYPROJECT["tool"]["setuptools"]["package-data"]["cvxgeodesic"]


def _public_callables():
    for name in cg.__all__:
        obj = getattr(cg, name)
        if inspect.isfunction(obj):
            yield name, obj
        elif inspect.isclass(obj) and not issubclass(obj, BaseException):
            for attr, member in vars(obj).items():
                # not the __init__ typing gives a Protocol (cvxgeodesic.Field): the package's own functions
                ours = member.__module__.startswith("cvxgeodesic") if inspect.isfunction(member) else False
                if ours and (not attr.startswith("_") or attr == "__init__"):
                    yield f"{name}.{attr}", member


def test_public_api_is_fully_annotated():
    missing = []
    for name, fn in _public_callables():
        sig = inspect.signature(fn)
        params = [p for p in sig.parameters.values() if p.name not in ("self", "cls")]
        missing += [f"{name}({p.name})" for p in params if p.annotation is inspect.Parameter.empty]
        if sig.return_annotation is inspect.Signature.empty:
            missing.append(f"{name} -> ?")
    assert missing == []


@needs_checkout
@pytest.mark.skipif(shutil.which("mypy") is None and not (Path(sys.executable).parent / "mypy").exists(),
                    reason="mypy not installed (the test extra)")
def test_mypy_is_clean_on_the_public_modules():
    res = subprocess.run([sys.executable, "-m", "mypy", "--cache-dir", str(ROOT / ".mypy_cache")], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    files = PYPROJECT["tool"]["mypy"]["files"]
    for module in ("api.py", "mesh/io.py", "mesh/trimesh.py", "errors.py", "__init__.py"):
        assert f"src/cvxgeodesic/{module}" in files


# ----------------------------------------------------------------------------------------------------------------------
# Item 7: small API points
# ----------------------------------------------------------------------------------------------------------------------


def test_plot_field_at_the_top_level():
    from cvxgeodesic import plot_field
    from cvxgeodesic.plotting import plot_field as original

    assert cg.plot_field is original and plot_field is original and "plot_field" in cg.__all__


def test_unknown_method_lists_every_method_baselines_included():
    with pytest.raises(cg.ParameterError) as exc:
        cg.GeodesicSolver(cg.icosphere(1), "dijkstar")
    for name in cg.ALL_METHODS:
        assert name in str(exc.value)


def _mesh_file(tmp_path):
    return cg.save_distance(tmp_path / "in.ply", cg.icosphere(1), np.zeros(42))


def test_comma_separated_sources(tmp_path, capsys):
    path = _mesh_file(tmp_path)
    for args, name in ((["-s", "0,5"], "a"), (["-s", "0", "-s", "5"], "b"), (["-s", "0,", "-s", "5"], "c")):
        out = tmp_path / f"{name}.npy"
        assert main(["distance", str(path), *args, "--method", "dijkstra", "-q", "-o", str(out)]) == 0
    a = np.load(tmp_path / "a.npy")
    np.testing.assert_array_equal(a, np.load(tmp_path / "b.npy"))
    np.testing.assert_array_equal(a, np.load(tmp_path / "c.npy"))
    assert a[0] == a[5] == 0.0
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        main(["distance", str(path), "-s", "0,x", "-o", str(tmp_path / "d.npy")])
    assert exc.value.code == 2 and "invalid vertex index list '0,x'" in capsys.readouterr().err


def test_png_marks_the_sources_and_labels_the_colour_bar(tmp_path, plot_field_calls):
    calls = plot_field_calls
    path = _mesh_file(tmp_path)
    rc = main(["distance", str(path), "-s", "3,7", "--method", "dijkstra", "-q", "-o", str(tmp_path / "d.ply"),
               "--png", str(tmp_path / "d.png")])
    assert rc == 0 and (tmp_path / "d.png").is_file()
    assert list(calls[0]["sources"]) == [3, 7]
    assert calls[0]["colorbar_label"] == "geodesic distance"


# ----------------------------------------------------------------------------------------------------------------------
# Item 1: installation
# ----------------------------------------------------------------------------------------------------------------------


@needs_checkout
def test_readme_documents_pip_install_and_every_extra():
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Install", 1)[1].split("\n## ", 1)[0]
    assert "pip install ." in section
    for extra in PYPROJECT["project"]["optional-dependencies"]:
        assert f"`{extra}`" in section, extra


@needs_checkout
def test_wheel_data_is_declared():
    data = PYPROJECT["tool"]["setuptools"]["package-data"]["cvxgeodesic"]
    assert "data/*" in data and (ROOT / "src" / "cvxgeodesic" / "data" / "spot.obj").is_file()
    extras = PYPROJECT["project"]["optional-dependencies"]
    assert {"pardiso", "cholmod", "cluster", "io", "test"} <= set(extras)
    assert any(r.startswith("mypy") for r in extras["test"])


@needs_checkout
@pytest.mark.slow
def test_built_wheel_contains_the_package_data(tmp_path):
    pytest.importorskip("build")
    # an isolated build (setuptools>=77 from the package index, as pip does)
    res = subprocess.run([sys.executable, "-m", "build", "--wheel", "--outdir", str(tmp_path)],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    import zipfile

    (wheel,) = tmp_path.glob("cvxgeodesic-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert {"cvxgeodesic/py.typed", "cvxgeodesic/data/spot.obj", "cvxgeodesic/mesh/fileorder.py"} <= names
