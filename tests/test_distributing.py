"""Distributing flanges (RBE3) against CalculiX 2.20 on exactly the builder's mesh.

A distributing flange's reference point moves as the weighted least-squares rigid motion of its
nodes and spreads its force and torque over them; nothing stiffens the part. CalculiX 2.20 has
this coupling in two halves, and the tests use each where it applies:
- `*DISTRIBUTING COUPLING` (a DCOUP3D element at the reference node): the reference node's
  translation is the weighted mean of the nodes' (its force spread as w_i F / W), printed
  directly. With the reference point at the nodes' weighted centroid (the builder's default) this
  is our coupling's translation exactly.
- `*COUPLING` + `*DISTRIBUTING`: forces and moments at a reference node spread over an element
  surface with CalculiX's own weights (the integral of each node's shape function over the faces,
  2 x 2 Gauss on 4-node faces: our `area` weights on hex8), at any reference point. CalculiX
  prints no reference motion for it: the reference point's displacement and rotation are read
  from CalculiX's displacement of the flange's nodes by the RBE3 definition (`rbe3_operator`
  below, written here from the definition, not taken from the builder).
- Moments on a tet10 bolt hole with uniform weights (which `*COUPLING` cannot take) are applied as
  the nodal loads of CalculiX's own distributing formula (cloaddistributing.f: f_i = w_i F + w_i
  (T^-1 M') x r_i, M' = M + (x_R - x_c) x F), checked against `*COUPLING` on the beam.
Each comparison holds to what CalculiX prints (7 significant digits): PRINTED = 1e-6.

Run with -s to see the measured deviations."""

import json
import zipfile

import numpy as np
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

import calculix as ccx
from conftest import EXAMPLES, run_builder
from test_calculix import PRINTED

NAMES = ["u_x", "u_y", "u_z", "phi_x", "phi_y", "phi_z"]


def build(spec, workdir, name):
    """Build `spec` (a dict) with its deck: (report.json, deck text, FMU path)."""
    path = workdir / f"{name}.json"
    path.write_text(json.dumps(spec))
    fmu, inp = workdir / f"{name}.fmu", workdir / f"{name}.inp"
    run_builder([path, "-o", fmu, "--export-inp", inp, "-q"])
    return json.loads(zipfile.ZipFile(fmu).read("documentation/report.json")), inp.read_text(), fmu


def weights(deck, flange):
    """{node: weight} of a distributing flange, from the deck's `**W node, weight` lines."""
    out, inside = {}, False
    for line in deck.splitlines():
        if line.startswith("** distributing coupling of "):
            inside = line.split(" of ")[1].split(" ")[0] == flange.upper()
        elif inside and line.startswith("**W "):
            node, w = line[4:].split(",")
            out[int(node)] = float(w)
    assert out, f"no weights of {flange} in the deck"
    return out


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def rbe3_operator(points, w, ref):
    """6 x 3n: the reference point's (u, theta) from the nodes' displacements, by the RBE3
    definition: the weighted least-squares rigid motion of the nodes (translation u_c + theta x
    (ref - x_c) at the reference point, theta = T^-1 sum w_i r_i x u_i, r_i = x_i - x_c)."""
    w = np.asarray(w) / np.sum(w)
    xc = w @ points
    r = points - xc
    t = sum(wi * (ri @ ri * np.eye(3) - np.outer(ri, ri)) for wi, ri in zip(w, r))
    t_inv = np.linalg.inv(t)
    c = np.zeros((6, 3 * len(points)))
    for i, (wi, ri) in enumerate(zip(w, r)):
        rot = wi * t_inv @ skew(ri)
        c[3:, 3 * i:3 * i + 3] = rot
        c[:3, 3 * i:3 * i + 3] = wi * np.eye(3) + skew(xc - ref) @ rot
    return c


def rbe3_loads(points, w, ref, force, moment):
    """CalculiX's distributing loads (cloaddistributing.f) of a force and moment at `ref`."""
    w = np.asarray(w) / np.sum(w)
    xc = w @ points
    r = points - xc
    t = sum(wi * (ri @ ri * np.eye(3) - np.outer(ri, ri)) for wi, ri in zip(w, r))
    m = np.asarray(moment) + np.cross(ref - xc, force)
    a = np.linalg.solve(t, m)
    return np.array([wi * np.asarray(force) + wi * np.cross(a, ri) for wi, ri in zip(w, r)])


def flange_nodes(deck, flange):
    ws = weights(deck, flange)
    coords = ccx.node_coordinates(deck)
    nodes = sorted(ws)
    return nodes, np.array([coords[n] for n in nodes]), np.array([ws[n] for n in nodes])


def reference_motion(result, nodes, points, w, ref):
    u = np.concatenate([result.u(n) for n in nodes])
    return rbe3_operator(points, w, ref) @ u


def compare(label, ours, theirs, scale):
    """Worst deviation of one compliance column, entry i relative to `scale[i]`."""
    assert len(ours) == len(theirs) == len(NAMES) == len(scale)
    worst = 0.0
    for name, a, b, s in zip(NAMES, ours, theirs, scale):
        dev = abs(a - b) / s
        worst = max(worst, dev)
        print(f"  {label} {name:6s} builder {a: .10e}  CalculiX {b: .6e}  deviation {dev:.1e}")
    return worst


def entry_scale(g, j):
    """The natural size of compliance entries (i, j): sqrt(G_ii G_jj), in their own units (a
    rotation per force and a displacement per force differ by a length)."""
    d = np.abs(np.diag(g))
    return np.sqrt(d * d[j])


def compliance(report, flange):
    i = report["accuracy"]["compliance_flanges"].index(flange)
    full = np.array(report["accuracy"]["compliance_full"])[6 * i:6 * i + 6, 6 * i:6 * i + 6]
    reduced = np.array(report["accuracy"]["compliance_reduced"])[6 * i:6 * i + 6, 6 * i:6 * i + 6]
    return full, reduced


# C3D8 faces by the positions of their nodes in the element (CalculiX's S1..S6)
C3D8_FACES = {1: (0, 1, 2, 3), 2: (4, 7, 6, 5), 3: (0, 4, 5, 1), 4: (1, 5, 6, 2), 5: (2, 6, 7, 3), 6: (3, 7, 4, 0)}


def surface(deck, nodes):
    """`*SURFACE` of the C3D8 faces whose four nodes all lie in `nodes`."""
    inside, lines = set(nodes), []
    for keyword, data in ccx._blocks(deck):
        if ccx._params(keyword)[""] != "*ELEMENT":
            continue
        for line in data:
            ids = [int(t) for t in line.split(",") if t.strip()]
            for label, face in C3D8_FACES.items():
                if all(ids[1 + k] in inside for k in face):
                    lines.append(f"{ids[0]}, S{label}")
    assert lines, "no element face on the flange"
    return "*SURFACE, NAME=TIPS, TYPE=ELEMENT\n" + "\n".join(lines) + "\n"


def compare_frequencies(label, ours, theirs, stiffer):
    """Our full model's frequencies against CalculiX's (7 printed digits: PRINTED) and below those
    of the same part with rigid couplings (1e-9: the two eigen-solves' round-off); the worst
    deviation and the largest stiffening."""
    assert len(ours) == len(theirs) == len(stiffer) > 0
    dev = np.abs(ours / theirs - 1)
    for k, (a, b, c) in enumerate(zip(ours, theirs, stiffer)):
        print(f"  mode {k + 1}: {label} {a:.6f} Hz, CalculiX {b:.6f} Hz ({dev[k]:.1e}), rigid {c:.6f} Hz "
              f"({c / a - 1:+.2e})")
    assert dev.max() <= PRINTED
    assert np.all(ours <= stiffer * (1 + 1e-9))
    return dev.max(), (stiffer / ours - 1).max()


def nodal_cload(nodes, loads):
    """`*CLOAD` of nodal forces (one row of `loads` per node), zero components left out."""
    return "*CLOAD\n" + "".join(f"{n}, {d + 1}, {ccx.fit_field(repr(float(f[d])))}\n"
                                for n, f in zip(nodes, loads) for d in range(3) if f[d] != 0.0)


def distributing_coupling(deck, nodes, ref_node):
    """CalculiX's `*COUPLING` + `*DISTRIBUTING` (forces and moments) of the C3D8 faces on `nodes`
    to `ref_node`."""
    return surface(deck, nodes) + (f"*COUPLING, REF NODE={ref_node}, SURFACE=TIPS, CONSTRAINT NAME=TIPC\n"
                                   "*DISTRIBUTING\n1, 6\n")


def beam_spec():
    """A hex8 cantilever, its tip a distributing flange with area weights and a reference point
    off the tip's centroid (so the moment of the offset enters)."""
    return {
        "name": "DistributedTip",
        "geometry": {"element": "hex8", "boxes": [{"min": [0, 0, 0], "max": [0.2, 0.02, 0.03],
                                                   "elements": [20, 4, 5]}]},
        "material": {"E": 2.1e11, "nu": 0.3, "rho": 7850},
        "flanges": [
            {"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}},
            {"name": "tip", "role": "force", "nodes": {"box_face": {"box": 0, "face": "+x"}},
             "coupling": "distributing", "weights": "area", "reference_point": [0.21, 0.013, 0.011]},
        ],
        "reduction": {"method": "craig_bampton", "modes": 8},
    }


def test_beam_tip_forces_and_moments_vs_calculix_coupling(tmp_path):
    """Each unit force and moment at the tip's reference point: the reference point's motion from
    CalculiX's *COUPLING + *DISTRIBUTING response against the builder's full-model compliance
    (and the reduced model's, a consistency check: constraint modes make statics exact)."""
    report, deck, _ = build(beam_spec(), tmp_path, "beam")
    nodes, points, w = flange_nodes(deck, "tip")
    ref = ccx.reference_point(deck, "tip")
    rot = ccx.set_node(deck, "TIP_ROT")
    full, reduced = compliance(report, "tip")
    coupling = ccx.rigid_body(deck, "base") + ccx.clamp(deck, "base") + distributing_coupling(deck, nodes, rot)
    worst = worst_reduced = 0.0
    for j in range(6):
        # by node number: a *CLOAD through a node set is lost for *COUPLING in CalculiX 2.20
        step = ccx.static_step(f"*CLOAD\n{rot}, {j + 1}, 1.0\n", prints=["TIP"])
        theirs = reference_motion(ccx.run_ccx(deck, coupling + step, tmp_path / f"c{j}"), nodes, points, w, ref)
        scale = entry_scale(full, j)
        worst = max(worst, compare(f"load {NAMES[j]}:", full[:, j], theirs, scale))
        worst_reduced = max(worst_reduced, (np.abs(reduced[:, j] - full[:, j]) / scale).max())
    print(f"beam tip (hex8, area weights, offset reference): worst deviation {worst:.1e} (entry (i, j) "
          f"relative to sqrt(G_ii G_jj)); reduced vs full {worst_reduced:.1e}")
    assert worst <= PRINTED
    # consistency: measured ~1e-15 (round-off of the reduced solve); 1e-12 leaves room
    assert worst_reduced <= 1e-12


def test_the_distributing_formula_is_calculix_coupling(tmp_path):
    """`rbe3_loads` (used for the bolt hole's moments) applied as nodal loads gives CalculiX's own
    *COUPLING + *DISTRIBUTING response on the beam: the formula is CalculiX's."""
    _, deck, _ = build(beam_spec(), tmp_path, "beam")
    nodes, points, w = flange_nodes(deck, "tip")
    ref = ccx.reference_point(deck, "tip")
    rot = ccx.set_node(deck, "TIP_ROT")
    base = ccx.rigid_body(deck, "base") + ccx.clamp(deck, "base")
    force, moment = (0.3, -0.2, 0.5), (0.01, 0.02, -0.015)
    cload = nodal_cload(nodes, rbe3_loads(points, w, ref, force, moment))
    explicit = ccx.run_ccx(deck, base + ccx.static_step(cload, prints=["TIP"]), tmp_path / "explicit")
    coupling = base + distributing_coupling(deck, nodes, rot)
    lines = "".join(f"{rot}, {d + 1}, {v!r}\n" for d, v in enumerate([*force, *moment]))
    native = ccx.run_ccx(deck, coupling + ccx.static_step("*CLOAD\n" + lines, prints=["TIP"]), tmp_path / "native")
    a = np.array([explicit.u(n) for n in nodes])
    b = np.array([native.u(n) for n in nodes])
    assert a.shape == b.shape
    dev = np.abs(a - b).max() / np.abs(b).max()
    print(f"\nexplicit distributing loads vs CalculiX *COUPLING: {dev:.1e}")
    assert dev <= PRINTED


def bracket_spec(coupling):
    spec = json.loads((EXAMPLES / "bracket" / "bracket.json").read_text())
    spec.pop("$schema", None)
    spec["geometry"]["mesh"] = str(EXAMPLES / "bracket" / "bracket.msh")
    arm = spec["flanges"][1]
    arm["coupling"] = coupling
    # the reference point at the hole's centroid (the default): CalculiX's DCOUP3D takes the
    # plain weighted mean, which is the coupling's translation there
    arm.pop("reference_point", None)
    return spec


def test_bracket_bolt_hole_vs_calculix(tmp_path):
    """The bracket's upright bolt hole (tet10, uniform weights) as a distributing flange: forces
    through CalculiX's *DISTRIBUTING COUPLING (reference translation printed by CalculiX), moments
    as CalculiX's distributing loads; the reference point's six motions from CalculiX's field."""
    report, deck, fmu = build(bracket_spec("distributing"), tmp_path, "bracket")
    # the report and the documentation say which flange distributes
    assert [f["coupling"] for f in report["flanges"]] == ["rigid", "distributing, uniform weights"]
    html = zipfile.ZipFile(fmu).read("documentation/index.html").decode()
    assert "<td>distributing, uniform weights</td>" in html
    nodes, points, w = flange_nodes(deck, "arm")
    assert np.allclose(w, 1.0)
    ref = ccx.reference_point(deck, "arm")
    ref_node = ccx.set_node(deck, "ARM_REF")
    full, reduced = compliance(report, "arm")
    base = ccx.rigid_body(deck, "base") + ccx.clamp(deck, "base")
    last_element = max(int(line.split(",")[0]) for keyword, data in ccx._blocks(deck)
                       if ccx._params(keyword)[""] == "*ELEMENT" for line in data if line[0].isdigit())
    dcoup = (f"*ELEMENT, TYPE=DCOUP3D, ELSET=ARMDC\n{last_element + 1}, {ref_node}\n"
             "*DISTRIBUTING COUPLING, ELSET=ARMDC\n" + "".join(f"{n}, 1.\n" for n in nodes))
    worst = worst_direct = 0.0
    for j in range(6):
        if j < 3:
            step = ccx.static_step(f"*CLOAD\n{ref_node}, {j + 1}, 1.0\n", prints=["ARM", "ARM_REF"])
            result = ccx.run_ccx(deck, base + dcoup + step, tmp_path / f"f{j}")
            # CalculiX's own reference translation
            direct = result.u(ref_node)
            worst_direct = max(worst_direct, np.abs(full[:3, j] - direct).max() / abs(direct[j]))
        else:
            moment = np.eye(3)[j - 3]
            cload = nodal_cload(nodes, rbe3_loads(points, w, ref, (0, 0, 0), moment))
            result = ccx.run_ccx(deck, base + ccx.static_step(cload, prints=["ARM"]), tmp_path / f"m{j}")
        theirs = reference_motion(result, nodes, points, w, ref)
        worst = max(worst, compare(f"load {NAMES[j]}:", full[:, j], theirs, entry_scale(full, j)))
        # consistency: the reduced model's statics are exact (constraint modes)
        assert np.abs(reduced[:, j] - full[:, j]).max() <= 1e-12 * abs(full[j, j])
    print(f"bracket bolt hole (tet10, uniform weights): worst deviation {worst:.1e}; reference translation "
          f"printed by CalculiX's DCOUP3D {worst_direct:.1e}")
    assert worst <= PRINTED
    assert worst_direct <= PRINTED


def test_bracket_frequencies_distributing_vs_calculix_and_rigid(tmp_path):
    """A distributing force flange adds no stiffness and no mass: the mounted bracket's full-model
    frequencies are the plain part's, as CalculiX computes them with the bolt hole free; and they
    lie below the rigid flange's (a rigid tie stiffens the hole), as theory requires."""
    dist, deck, fmu = build(bracket_spec("distributing"), tmp_path, "dist")
    rigid, _, _ = build(bracket_spec("rigid"), tmp_path, "rigid")
    count = 10
    base = ccx.rigid_body(deck, "base") + ccx.clamp(deck, "base")
    result = ccx.run_ccx(deck, base + ccx.frequency_step(count), tmp_path / "freq")
    ours = np.array(dist["accuracy"]["full_hz"][:count])
    theirs = np.array(result.frequencies_hz[:count])
    stiff = np.array(rigid["accuracy"]["full_hz"][:count])
    assert len(ours) == count
    # the hole's own stiffening visible in some modes (measured +1e-3 .. +5e-2 on those it loads)
    assert compare_frequencies("distributing", ours, theirs, stiff)[1] > 1e-3
    # the FMU of a distributing flange is a standard FMU for FMPy
    assert validate_fmu(str(fmu)) == []
    out = simulate_fmu(str(fmu), stop_time=0.01, fmi_type="CoSimulation", output=["arm.u[1]", "arm.phi[2]"])
    assert np.all(np.isfinite(out["arm.u[1]"])) and np.all(np.isfinite(out["arm.phi[2]"]))


def test_distributing_mount_frequencies_vs_calculix_equations(tmp_path):
    """A distributing mount: the body frame follows its nodes' weighted least-squares motion, so
    clamping the mount holds the six constraints C u = 0, not the nodes. CalculiX 2.20 has no
    keyword for the rotational half, so the six constraints go in as `*EQUATION`s written here from
    the RBE3 definition (`rbe3_operator`, brought to reduced row echelon form so that each
    equation has its own dependent DoF); CalculiX's frequencies of the beam held that way against
    the builder's full model, and below the rigid mount's."""
    spec = json.loads((EXAMPLES / "beam.json").read_text())
    spec.pop("$schema", None)
    spec["geometry"]["boxes"][0]["elements"] = [20, 2, 2]
    rigid, _, _ = build(spec, tmp_path, "rigid")
    spec["flanges"][0]["coupling"] = "distributing"
    report, deck, _ = build(spec, tmp_path, "mount")
    nodes, points, w = flange_nodes(deck, "base")
    c = rbe3_operator(points, w, ccx.reference_point(deck, "base"))
    # six pivot columns by complete pivoting, then each row with only its own pivot
    work, pivots, rows = c.copy(), [], list(range(6))
    for _ in range(6):
        sub = np.abs(work[rows])
        sub[:, pivots] = 0.0
        i, j = np.unravel_index(np.argmax(sub), sub.shape)
        r = rows.pop(i)
        pivots.append(j)
        for q in rows:
            work[q] -= work[q, j] / work[r, j] * work[r]
    e = np.linalg.solve(c[:, pivots], c)
    equations = ""
    for k, p in enumerate(pivots):
        others = [m for m in range(e.shape[1]) if m not in pivots and abs(e[k, m]) > 1e-14]
        terms = [(nodes[m // 3], m % 3 + 1, e[k, m]) for m in [p, *others]]
        equations += f"*EQUATION\n{len(terms)}\n"
        for i in range(0, len(terms), 4):
            equations += ", ".join(f"{n}, {d}, {ccx.fit_field(repr(float(v)))}" for n, d, v in terms[i:i + 4]) + "\n"
    count = 8
    result = ccx.run_ccx(deck, ccx.rigid_body(deck, "tip") + equations + ccx.frequency_step(count), tmp_path / "freq")
    ours = np.array(report["accuracy"]["full_hz"][:count])
    theirs = np.array(result.frequencies_hz[:count])
    stiff = np.array(rigid["accuracy"]["full_hz"][:count])
    assert len(ours) == count
    # measured 4.1e-7 at most: CalculiX's 7 printed digits; the rigid mount 0.6-1.4 % stiffer
    assert compare_frequencies("distributing mount", ours, theirs, stiff)[1] > 1e-4


def test_free_body_with_distributing_flanges_keeps_the_plain_parts_frequencies(tmp_path):
    """A free-floating bracket whose two bolt holes are distributing force flanges: nothing is added
    to the part, so its free-free frequencies (full model and, to the reduction's accuracy, the
    FMU's) are CalculiX's for the plain part (`*FREQUENCY` above a 1 Hz shift, the rigid-body
    modes below it); rigid flanges stiffen both holes and raise them."""
    spec = bracket_spec("distributing")
    spec["flanges"][0]["role"] = "force"
    spec["flanges"][0]["coupling"] = "distributing"
    spec["flanges"][0].pop("reference_point", None)
    report, deck, fmu = build(spec, tmp_path, "free")
    for f in spec["flanges"]:
        f["coupling"] = "rigid"
    rigid, _, _ = build(spec, tmp_path, "free_rigid")
    count = 8
    result = ccx.run_ccx(deck, ccx.frequency_step(count + 6, shift_hz=1.0), tmp_path / "freq")
    ours = np.array(report["accuracy"]["full_hz"][:count])
    theirs = np.array(result.frequencies_hz[:count])
    stiff = np.array(rigid["accuracy"]["full_hz"][:count])
    assert len(ours) == count and theirs[0] > 100.0
    assert compare_frequencies("free, distributing holes", ours, theirs, stiff)[1] > 1e-4
    assert validate_fmu(str(fmu)) == []
