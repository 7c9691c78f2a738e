"""The example bracket (examples/bracket/bracket.geo) meshed by Gmsh at another element size.

The benchmark needs the same part at 2e4 ... 1e6 DoF. The .geo is copied into a work
directory with its sizes changed and opened with the Gmsh Python API; the .geo's own Save
commands write bracket.inp and bracket.msh next to the copy, so the node sets BOLT_BASE and
BOLT_ARM and the element set BRACKET are those the example's builder input names.

Meshes are cached per element size: a directory that already holds a complete bracket.inp is
reused, so reruns skip Gmsh (minutes at 1e6 DoF).

    python bench/bracket_mesh.py 0.0016 target/builder-bench    # prints the .inp's path

Needs gmsh==4.15.2 (PyPI), the version the example was made with; tests/run.sh installs it into
tests/.venv.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GEO = ROOT / "examples" / "bracket" / "bracket.geo"
GMSH_VERSION = "4.15.2"
#: written last, after Gmsh returned: a directory without it holds an interrupted run
DONE = "mesh.done"


def sized_geo(lc: float) -> str:
    """bracket.geo with global size `lc`, hole size min(0.0025, 0.6 lc) (the holes stay finer than
    the rest, as in the example) and the minimum size min(0.001, lc / 3) (else Gmsh's floor of
    1 mm would stop refinement below lc = 3 mm)."""
    text = GEO.read_text()
    replacements = [
        (r"^lc = [^;]*;", f"lc = {lc!r};"),
        (r"^lc_hole = [^;]*;", f"lc_hole = {min(0.0025, 0.6 * lc)!r};"),
        (r"^Mesh\.MeshSizeMin = [^;]*;", f"Mesh.MeshSizeMin = {min(0.001, lc / 3)!r};"),
    ]
    for pattern, new in replacements:
        text, n = re.subn(pattern, new, text, count=1, flags=re.M)
        if n != 1:
            raise RuntimeError(f"{GEO}: no line matching {pattern!r} (has the example changed?)")
    return text


def mesh_dir(work: Path, lc: float) -> Path:
    return Path(work) / f"bracket-lc{lc:.6g}"


def import_gmsh():
    try:
        import gmsh
    except ImportError as e:
        raise RuntimeError(
            f"the Gmsh Python API is missing: `{sys.executable} -m pip install gmsh=={GMSH_VERSION}` "
            "(or run bash tests/run.sh, which installs it into tests/.venv)") from e
    if gmsh.__version__ != GMSH_VERSION:
        print(f"warning: gmsh {gmsh.__version__}, the example was meshed with {GMSH_VERSION}", file=sys.stderr)
    return gmsh


def bracket_mesh(lc: float, work: Path) -> Path:
    """Path of bracket.inp meshed at global size `lc` [m] under `work`, made if not cached."""
    out = mesh_dir(work, lc)
    inp = out / "bracket.inp"
    if (out / DONE).exists() and inp.exists():
        return inp
    out.mkdir(parents=True, exist_ok=True)
    (out / "bracket.geo").write_text(sized_geo(lc))
    gmsh = import_gmsh()
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(out / "bracket.geo"))  # meshes and saves (the .geo's last lines)
    finally:
        gmsh.finalize()
    if not inp.exists():
        raise RuntimeError(f"Gmsh wrote no {inp}")
    (out / DONE).write_text(f"gmsh {gmsh.__version__}, lc {lc!r}\n")
    return inp


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    print(bracket_mesh(float(argv[1]), Path(argv[2])))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
