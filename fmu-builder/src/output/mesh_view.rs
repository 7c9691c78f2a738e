//! Pictures of the part for the documentation, as inline SVG: the outline of the mesh (its
//! feature edges: boundary edges where the surface folds by more than 30 degrees) in an
//! isometric view, with each flange's slave nodes and reference point; and mode shapes, the
//! outline displaced over the undeformed one in grey. Small whatever the mesh: a 250k-node
//! part draws a few thousand lines.

use crate::model::flange::{Flange, model_size};
use crate::model::part::Part;
use crate::output::plot::{PALETTE, esc};
use faer::MatRef;
use std::collections::HashMap;
use std::fmt::Write;

const WIDTH: f64 = 640.0;
const HEIGHT: f64 = 400.0;
const MARGIN: f64 = 30.0;
/// Width kept free at the left for the axis triad, so that the part never hides it.
const TRIAD_COLUMN: f64 = 60.0;
/// Length of a triad arrow whose axis lies in the page plane [px].
const TRIAD_LENGTH: f64 = 30.0;
/// Font size of the flange labels [px]; their width is estimated from it.
const LABEL_SIZE: f64 = 13.0;
/// Most slave nodes drawn per flange (evenly thinned beyond).
const MAX_DOTS: usize = 400;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if n > 0.0 { [a[0] / n, a[1] / n, a[2] / n] } else { a }
}

/// Feature edges of the mesh's surface, as pairs of corner nodes.
pub fn outline(part: &Part) -> Vec<[usize; 2]> {
    let mesh = &part.mesh;
    // each boundary edge with the normals of the boundary faces along it
    let mut edges: HashMap<[usize; 2], Vec<[f64; 3]>> = HashMap::new();
    for (e, f) in mesh.boundary_faces() {
        let conn = mesh.element(e);
        let nodes: Vec<usize> = mesh.kind(e).corner_faces()[f].iter().map(|&i| conn[i]).collect();
        let p = |i: usize| mesh.nodes[nodes[i]];
        let normal = unit(cross(sub(p(1), p(0)), sub(p(2), p(0))));
        for i in 0..nodes.len() {
            let (a, b) = (nodes[i], nodes[(i + 1) % nodes.len()]);
            edges.entry([a.min(b), a.max(b)]).or_default().push(normal);
        }
    }
    let fold = 30f64.to_radians().cos();
    let mut out: Vec<[usize; 2]> = edges
        .into_iter()
        .filter(|(_, normals)| {
            normals.len() != 2 || {
                let (a, b) = (normals[0], normals[1]);
                (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).abs() < fold
            }
        })
        .map(|(e, _)| e)
        .collect();
    out.sort_unstable();
    out
}

/// The smallest and largest of each coordinate of 2-D points (the box a picture must hold).
fn bounds(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    points.fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), q| {
        ([lo[0].min(q[0]), lo[1].min(q[1])], [hi[0].max(q[0]), hi[1].max(q[1])])
    })
}

/// Isometric projection (view from (1, -1, 1), z up) onto the page.
struct View {
    right: [f64; 3],
    up: [f64; 3],
    scale: f64,
    offset: [f64; 2],
}

impl View {
    fn fit(points: impl Iterator<Item = [f64; 3]> + Clone) -> Self {
        let d = unit([1.0, -1.0, 1.0]);
        let right = unit(cross([0.0, 0.0, 1.0], d));
        let up = cross(d, right);
        let mut v = View { right, up, scale: 1.0, offset: [0.0, 0.0] };
        let (lo, hi) = bounds(points.map(|p| v.raw(p)));
        let span = [(hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300)];
        let (left, width) = (MARGIN + TRIAD_COLUMN, WIDTH - 2.0 * MARGIN - TRIAD_COLUMN);
        v.scale = (width / span[0]).min((HEIGHT - 2.0 * MARGIN) / span[1]);
        v.offset = [
            left + 0.5 * (width - span[0] * v.scale) - lo[0] * v.scale,
            MARGIN + 0.5 * (HEIGHT - 2.0 * MARGIN - span[1] * v.scale) + hi[1] * v.scale,
        ];
        v
    }

    fn raw(&self, p: [f64; 3]) -> [f64; 2] {
        let dot = |a: [f64; 3]| a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
        [dot(self.right), dot(self.up)]
    }

    fn page(&self, p: [f64; 3]) -> [f64; 2] {
        let q = self.raw(p);
        [self.offset[0] + q[0] * self.scale, self.offset[1] - q[1] * self.scale]
    }

    /// Page direction of a model direction (page y points down), unscaled: an axis in the page
    /// plane has length 1, one along the line of sight 0.
    fn direction(&self, a: [f64; 3]) -> [f64; 2] {
        let q = self.raw(a);
        [q[0], -q[1]]
    }
}

/// The x, y, z axes as arrows from a common origin in the lower-left corner, projected by `view`
/// as the part is, so that the picture's directions can be read off.
fn triad(view: &View) -> String {
    let axes = [("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0]), ("z", [0.0, 0.0, 1.0])];
    let dirs: Vec<[f64; 2]> = axes.iter().map(|(_, a)| view.direction(*a)).collect();
    // the labels sit beyond the tips: the corner holds tips and labels
    let reach = |d: [f64; 2], k: usize| d[k] * (TRIAD_LENGTH + 10.0);
    let lo = |k: usize| dirs.iter().map(|d| reach(*d, k)).fold(0.0f64, f64::min);
    let hi = |k: usize| dirs.iter().map(|d| reach(*d, k)).fold(0.0f64, f64::max);
    let origin = [12.0 - lo(0), HEIGHT - 12.0 - hi(1)];
    let mut s =
        String::from("<g class=\"triad\" stroke=\"#333\" fill=\"#333\" font-family=\"sans-serif\" font-size=\"12\">\n");
    for ((name, _), d) in axes.iter().zip(&dirs) {
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        let o = origin;
        if len < 0.15 {
            // along the line of sight: a dot at the origin and the label beside it
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\"/><text x=\"{:.1}\" y=\"{:.1}\" stroke=\"none\">{name}</text>",
                o[0],
                o[1],
                o[0] + 5.0,
                o[1] + 12.0
            );
            continue;
        }
        let tip = [o[0] + TRIAD_LENGTH * d[0], o[1] + TRIAD_LENGTH * d[1]];
        let u = [d[0] / len, d[1] / len];
        let (back, side) = (7.0, 3.5);
        let base = [tip[0] - back * u[0], tip[1] - back * u[1]];
        let _ = writeln!(
            s,
            "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke-width=\"1.5\"/>\
<polygon points=\"{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}\" stroke=\"none\"/>\
<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" dominant-baseline=\"central\" stroke=\"none\">{name}</text>",
            o[0],
            o[1],
            base[0],
            base[1],
            tip[0],
            tip[1],
            base[0] - side * u[1],
            base[1] + side * u[0],
            base[0] + side * u[1],
            base[1] - side * u[0],
            tip[0] + 9.0 * u[0],
            tip[1] + 9.0 * u[1],
        );
    }
    s.push_str("</g>\n");
    s
}

fn svg_open(title: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{HEIGHT}\" viewBox=\"0 0 {WIDTH} {HEIGHT}\" \
role=\"img\" aria-label=\"{t}\"><title>{t}</title><rect width=\"{WIDTH}\" height=\"{HEIGHT}\" fill=\"white\"/>\n",
        t = esc(title)
    )
}

fn path_of(view: &View, edges: &[[usize; 2]], at: &dyn Fn(usize) -> [f64; 3]) -> String {
    let mut d = String::new();
    for e in edges {
        let (a, b) = (view.page(at(e[0])), view.page(at(e[1])));
        let _ = write!(d, "M{:.1} {:.1}L{:.1} {:.1}", a[0], a[1], b[0], b[1]);
    }
    d
}

/// The outline with every flange's slave nodes (dots) and reference point (a cross), each flange
/// labelled beside its nodes, and the axis triad. The dots lie under the outline, half
/// transparent, as they crowd exactly where the flanges' holes are; the labels sit outside the
/// cluster on a leader line, with a white halo over whatever they cross.
pub fn mesh_picture(part: &Part, flanges: &[Flange], edges: &[[usize; 2]]) -> String {
    let nodes = &part.mesh.nodes;
    let all = edges.iter().flat_map(|e| [nodes[e[0]], nodes[e[1]]]).chain(flanges.iter().map(|f| f.reference));
    let view = View::fit(all.clone());
    // the part's middle on the page: labels move away from it
    let (lo, hi) = bounds(all.map(|p| view.page(p)));
    let middle = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let mut s = svg_open("the mesh's outline, flanges' slave nodes and reference points");
    let mut clusters = Vec::new();
    for (k, f) in flanges.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let step = f.slaves.len().div_ceil(MAX_DOTS).max(1);
        let r = view.page(f.reference);
        let mut radius = 0.0f64;
        for &n in f.slaves.iter().step_by(step) {
            let p = view.page(nodes[n]);
            radius = radius.max((p[0] - r[0]).hypot(p[1] - r[1]));
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"1.6\" fill=\"{colour}\" fill-opacity=\"0.45\"/>",
                p[0], p[1]
            );
        }
        clusters.push(radius);
    }
    let _ = writeln!(
        s,
        "<path d=\"{}\" stroke=\"#444\" stroke-width=\"0.7\" fill=\"none\"/>",
        path_of(&view, edges, &|i| nodes[i])
    );
    let mut placed: Vec<[f64; 4]> = Vec::new();
    for (k, f) in flanges.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let r = view.page(f.reference);
        let text =
            format!("{} ({})", f.name, if f.role == crate::input::spec::Role::Motion { "mount" } else { "force" });
        let (anchor, end) = label_place(r, middle, clusters[k], &text, &mut placed);
        let _ = writeln!(
            s,
            "<path d=\"M{x0:.1} {y:.1}L{x1:.1} {y:.1}M{x:.1} {y0:.1}L{x:.1} {y1:.1}\" stroke=\"{colour}\" stroke-width=\"2\"/>\
<path d=\"M{x:.1} {y:.1}L{ax:.1} {ay:.1}\" stroke=\"{colour}\" stroke-width=\"1\"/>\
<text class=\"flange-label\" x=\"{ax:.1}\" y=\"{ty:.1}\" text-anchor=\"{end}\" font-size=\"{LABEL_SIZE}\" \
font-family=\"sans-serif\" fill=\"{colour}\" stroke=\"white\" stroke-width=\"4\" stroke-linejoin=\"round\" \
paint-order=\"stroke\">{name}</text>",
            x0 = r[0] - 7.0,
            x1 = r[0] + 7.0,
            x = r[0],
            y = r[1],
            y0 = r[1] - 7.0,
            y1 = r[1] + 7.0,
            ax = anchor[0],
            ay = anchor[1],
            ty = anchor[1] + 0.35 * LABEL_SIZE,
            name = esc(&text),
        );
    }
    s.push_str(&triad(&view));
    s.push_str("</svg>\n");
    s
}

/// Where a flange's label goes: from its reference point `r` away from the part's `middle`, past
/// the flange's node cluster (`radius` px), inside the picture, and below any label already
/// `placed` (boxes x0, y0, x1, y1) it would overlap. Returns the leader line's end (the text's
/// left or right middle) and the text anchor.
fn label_place(
    r: [f64; 2],
    middle: [f64; 2],
    radius: f64,
    text: &str,
    placed: &mut Vec<[f64; 4]>,
) -> ([f64; 2], &'static str) {
    let mut d = [r[0] - middle[0], r[1] - middle[1]];
    let len = d[0].hypot(d[1]);
    // a reference point at the middle: up and to the right, where the isometric view leaves room
    d = if len > 1.0 {
        [d[0] / len, d[1] / len]
    } else {
        [std::f64::consts::FRAC_1_SQRT_2, -std::f64::consts::FRAC_1_SQRT_2]
    };
    let distance = radius.min(120.0) + 18.0;
    let width = 0.6 * LABEL_SIZE * text.chars().count() as f64;
    let mut p = [r[0] + distance * d[0], r[1] + distance * d[1]];
    let mut end = if d[0] >= 0.0 { "start" } else { "end" };
    // the text's box must stay in the picture: turn it round at an edge, then clamp
    if end == "start" && p[0] + width > WIDTH - 4.0 {
        end = "end";
    } else if end == "end" && p[0] - width < 4.0 {
        end = "start";
    }
    let extent = |p: [f64; 2], end: &str| {
        let x0 = if end == "start" { p[0] } else { p[0] - width };
        [x0, p[1] - 0.6 * LABEL_SIZE, x0 + width, p[1] + 0.6 * LABEL_SIZE]
    };
    let b = extent(p, end);
    p[0] += (4.0 - b[0]).max(0.0) - (b[2] - (WIDTH - 4.0)).max(0.0);
    p[1] = p[1].clamp(LABEL_SIZE, HEIGHT - LABEL_SIZE);
    let overlaps = |a: [f64; 4], b: &[f64; 4]| a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
    for _ in 0..20 {
        let b = extent(p, end);
        if !placed.iter().any(|q| overlaps(b, q)) {
            break;
        }
        p[1] = if p[1] + 1.4 * LABEL_SIZE > HEIGHT - LABEL_SIZE {
            p[1] - 6.0 * LABEL_SIZE
        } else {
            p[1] + 1.4 * LABEL_SIZE
        };
    }
    placed.push(extent(p, end));
    (p, end)
}

/// Mode `j` of the fields `shapes` (3N x k): the outline displaced (largest displacement a
/// tenth of the part's size) over the undeformed outline in grey.
pub fn mode_picture(part: &Part, edges: &[[usize; 2]], shapes: MatRef<'_, f64>, j: usize, hz: f64) -> String {
    let nodes = &part.mesh.nodes;
    let size = model_size(&part.mesh);
    let u = |i: usize| [shapes[(3 * i, j)], shapes[(3 * i + 1, j)], shapes[(3 * i + 2, j)]];
    let largest = edges
        .iter()
        .flat_map(|e| [e[0], e[1]])
        .map(|i| {
            let v = u(i);
            (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
        })
        .fold(0.0f64, f64::max);
    let scale = if largest > 0.0 { 0.1 * size / largest } else { 0.0 };
    let moved = |i: usize| {
        let (p, v) = (nodes[i], u(i));
        [p[0] + scale * v[0], p[1] + scale * v[1], p[2] + scale * v[2]]
    };
    let view = View::fit(edges.iter().flat_map(|e| [nodes[e[0]], nodes[e[1]], moved(e[0]), moved(e[1])]));
    let mut s = svg_open(&format!("mode {} at {hz:.4} Hz", j + 1));
    let _ = writeln!(
        s,
        "<path d=\"{}\" stroke=\"#bbb\" stroke-width=\"0.6\" fill=\"none\"/>",
        path_of(&view, edges, &|i| nodes[i])
    );
    let _ = writeln!(
        s,
        "<path d=\"{}\" stroke=\"{}\" stroke-width=\"0.9\" fill=\"none\"/>",
        path_of(&view, edges, &moved),
        PALETTE[0]
    );
    let _ = writeln!(
        s,
        "<text x=\"10\" y=\"20\" font-size=\"14\" font-family=\"sans-serif\">mode {} at {hz:.4} Hz (displacement scaled to a tenth of the part's size)</text>",
        j + 1
    );
    s.push_str(&triad(&view));
    s.push_str("</svg>\n");
    s
}

/// The documentation's pictures (caption, SVG): the mesh with its flanges, and the first three
/// modes of `shapes` (the basis on the mesh, 3N x r) at `omega` [rad/s]. None for matrix input.
pub fn pictures(part: &Part, flanges: &[Flange], shapes: MatRef<'_, f64>, omega: &[f64]) -> Vec<(String, String)> {
    if !part.has_elements() {
        return Vec::new();
    }
    let edges = outline(part);
    let mut out = vec![(
        "The mesh's outline (its feature edges, holes included; isometric view, z up), each flange's slave nodes and \
its reference point (labelled)"
            .to_string(),
        mesh_picture(part, flanges, &edges),
    )];
    for j in 0..3.min(shapes.ncols()).min(omega.len()) {
        let hz = omega[j] / (2.0 * std::f64::consts::PI);
        out.push((
            format!("Mode {} of the reduced body, {hz:.4} Hz", j + 1),
            mode_picture(part, &edges, shapes, j, hz),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::element::ElementKind;
    use crate::input::mesh::{BoxRegion, mesh_boxes};
    use crate::input::spec::Role;
    use crate::model::flange::FlangeCoupling;
    use crate::output::plot::tests::check_svg;
    use std::collections::BTreeMap;

    /// A 3 x 3 x 1 plate with a 1 x 1 hole through its middle (four boxes round it), one hex8 per
    /// unit cube.
    fn plate_with_hole() -> Part {
        let b = |min: [f64; 3], max: [f64; 3]| BoxRegion {
            min,
            max,
            divisions: [(max[0] - min[0]) as usize, (max[1] - min[1]) as usize, 1],
        };
        let boxes = vec![
            b([0.0, 0.0, 0.0], [3.0, 1.0, 1.0]),
            b([0.0, 2.0, 0.0], [3.0, 3.0, 1.0]),
            b([0.0, 1.0, 0.0], [1.0, 2.0, 1.0]),
            b([2.0, 1.0, 0.0], [3.0, 2.0, 1.0]),
        ];
        Part {
            mesh: mesh_boxes(&boxes, ElementKind::Hex8).expect("mesh"),
            boxes,
            materials: Vec::new(),
            node_sets: BTreeMap::new(),
            matrices: None,
            rigid_body_residual: None,
            source: "4 boxes".into(),
            from_matrices: false,
            origin: "test.json".into(),
            node_ids: Vec::new(),
            element_ids: Vec::new(),
            length_scale: 1.0,
            notes: Vec::new(),
        }
    }

    fn flange(part: &Part, name: &str, role: Role, at: impl Fn([f64; 3]) -> bool, reference: [f64; 3]) -> Flange {
        let slaves = (0..part.mesh.nodes.len()).filter(|&n| at(part.mesh.nodes[n])).collect();
        Flange { name: name.into(), role, reference, slaves, coupling: FlangeCoupling::Rigid }
    }

    /// Segments "Mx yLx y" of the first path with `stroke`.
    fn segments(svg: &str, stroke: &str) -> usize {
        let at = svg.find(&format!("\" stroke=\"{stroke}\"")).expect("path");
        let d = &svg[svg[..at].rfind("d=\"").expect("d") + 3..at];
        d.matches('M').count()
    }

    #[test]
    fn the_mesh_picture_draws_the_hole() {
        let part = plate_with_hole();
        let edges = outline(&part);
        let on_hole = |p: [f64; 3]| (1.0..=2.0).contains(&p[0]) && (1.0..=2.0).contains(&p[1]);
        let nodes = &part.mesh.nodes;
        // the hole's four vertical edges and its rims on both faces
        let hole = edges.iter().filter(|e| on_hole(nodes[e[0]]) && on_hole(nodes[e[1]])).count();
        assert_eq!(hole, 4 + 2 * 4);
        let flanges = [
            flange(&part, "base", Role::Motion, |p| p[0] == 0.0, [0.0, 1.5, 0.5]),
            flange(&part, "bolt", Role::Force, on_hole, [1.5, 1.5, 0.5]),
        ];
        let svg = mesh_picture(&part, &flanges, &edges);
        check_svg(&svg);
        // every feature edge drawn, as in the mode pictures, not the 12 of the bounding box
        assert_eq!(segments(&svg, "#444"), edges.len());
        let shapes =
            faer::Mat::<f64>::from_fn(3 * nodes.len(), 1, |i, _| if i % 3 == 2 { nodes[i / 3][0] } else { 0.0 });
        let mode = mode_picture(&part, &edges, shapes.as_ref(), 0, 10.0);
        check_svg(&mode);
        assert_eq!(segments(&mode, "#bbb"), edges.len());
        // the outline over the dots: the hole's rim is not painted over by its flange's nodes
        assert!(svg.find("stroke=\"#444\"") > svg.rfind("<circle"));
    }

    #[test]
    fn flange_labels_stand_clear_of_their_nodes() {
        let part = plate_with_hole();
        let edges = outline(&part);
        let on_hole = |p: [f64; 3]| (1.0..=2.0).contains(&p[0]) && (1.0..=2.0).contains(&p[1]);
        let flanges = [
            flange(&part, "bolt", Role::Force, on_hole, [1.5, 1.5, 0.5]),
            flange(&part, "edge", Role::Force, |p| p[0] == 3.0, [3.0, 1.5, 0.5]),
            flange(&part, "base", Role::Motion, |p| p[0] == 0.0, [0.0, 1.5, 0.5]),
        ];
        let svg = mesh_picture(&part, &flanges, &edges);
        let view = View::fit(edges.iter().flat_map(|e| [part.mesh.nodes[e[0]], part.mesh.nodes[e[1]]]));
        let mut boxes = Vec::new();
        for f in &flanges {
            let role = if f.role == Role::Motion { "mount" } else { "force" };
            let text = format!("{} ({role})</text>", f.name);
            let at = svg.find(&text).unwrap_or_else(|| panic!("{text} missing: {svg}"));
            let tag = &svg[svg[..at].rfind("<text").unwrap()..at];
            assert!(tag.contains("paint-order=\"stroke\"") && tag.contains("stroke=\"white\""), "{tag}");
            let num = |key: &str| -> f64 {
                let v = &tag[tag.find(&format!(" {key}=\"")).unwrap() + key.len() + 3..];
                v[..v.find('"').unwrap()].parse().unwrap()
            };
            let (x, y) = (num("x"), num("y"));
            assert!((0.0..=WIDTH).contains(&x) && (0.0..=HEIGHT).contains(&y), "{tag}");
            // beyond every drawn slave node of its flange (the largest clusters, a whole face, are
            // left at 120 px: beyond them the label would leave the picture)
            let r = view.page(f.reference);
            let cluster =
                f.slaves.iter().map(|&n| view.page(part.mesh.nodes[n])).map(|p| (p[0] - r[0]).hypot(p[1] - r[1]));
            let radius = cluster.fold(0.0, f64::max);
            assert!((x - r[0]).hypot(y - r[1]) > radius.min(120.0) + 10.0, "{tag}: {radius}");
            boxes.push((x, y));
        }
        // no two labels on top of each other
        for i in 0..boxes.len() {
            for j in 0..i {
                assert!((boxes[i].0 - boxes[j].0).abs() > 40.0 || (boxes[i].1 - boxes[j].1).abs() > LABEL_SIZE);
            }
        }
    }

    #[test]
    fn the_triad_points_as_the_projection_does() {
        let part = plate_with_hole();
        let edges = outline(&part);
        let view = View::fit(edges.iter().flat_map(|e| [part.mesh.nodes[e[0]], part.mesh.nodes[e[1]]]));
        let svg = mesh_picture(&part, &[], &edges);
        let g = &svg[svg.find("<g class=\"triad\"").expect("triad")..];
        let g = &g[..g.find("</g>").unwrap()];
        for (k, name) in ["x", "y", "z"].iter().enumerate() {
            // the label beyond the arrow's tip, in the direction a step along the axis moves on the page
            let at = g.find(&format!(">{name}</text>")).unwrap_or_else(|| panic!("{name}: {g}"));
            let line = &g[g[..at].rfind("<line").unwrap()..at];
            let num = |key: &str| -> f64 {
                let v = &line[line.find(&format!(" {key}=\"")).unwrap() + key.len() + 3..];
                v[..v.find('"').unwrap()].parse().unwrap()
            };
            let arrow = [num("x2") - num("x1"), num("y2") - num("y1")];
            let mut e = [0.0; 3];
            e[k] = 1.0;
            let (a, b) = (view.page([0.0; 3]), view.page(e));
            let step = [b[0] - a[0], b[1] - a[1]];
            let cos = (arrow[0] * step[0] + arrow[1] * step[1]) / (arrow[0].hypot(arrow[1]) * step[0].hypot(step[1]));
            assert!(cos > 0.999, "{name}: arrow {arrow:?}, page step {step:?}");
            // inside the picture, in the column kept free for it
            assert!(num("x1") < MARGIN + TRIAD_COLUMN && num("x1") > 0.0 && num("y1") < HEIGHT);
        }
    }
}
