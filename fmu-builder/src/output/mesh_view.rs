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
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            let q = v.raw(p);
            for a in 0..2 {
                lo[a] = lo[a].min(q[a]);
                hi[a] = hi[a].max(q[a]);
            }
        }
        let span = [(hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300)];
        v.scale = ((WIDTH - 2.0 * MARGIN) / span[0]).min((HEIGHT - 2.0 * MARGIN) / span[1]);
        v.offset = [
            MARGIN + 0.5 * (WIDTH - 2.0 * MARGIN - span[0] * v.scale) - lo[0] * v.scale,
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
}

fn svg_open(title: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{HEIGHT}\" viewBox=\"0 0 {WIDTH} {HEIGHT}\" \
role=\"img\" aria-label=\"{t}\"><title>{t}</title><rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
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

/// The outline with every flange's slave nodes (dots) and reference point (a cross, labelled).
pub fn mesh_picture(part: &Part, flanges: &[Flange], edges: &[[usize; 2]]) -> String {
    let nodes = &part.mesh.nodes;
    let all = edges.iter().flat_map(|e| [nodes[e[0]], nodes[e[1]]]).chain(flanges.iter().map(|f| f.reference));
    let view = View::fit(all);
    let mut s = svg_open("the mesh's outline, flanges' slave nodes and reference points");
    let _ = writeln!(
        s,
        "<path d=\"{}\" stroke=\"#444\" stroke-width=\"0.7\" fill=\"none\"/>",
        path_of(&view, edges, &|i| nodes[i])
    );
    for (k, f) in flanges.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let step = f.slaves.len().div_ceil(MAX_DOTS).max(1);
        for &n in f.slaves.iter().step_by(step) {
            let p = view.page(nodes[n]);
            let _ = writeln!(s, "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"1.6\" fill=\"{colour}\"/>", p[0], p[1]);
        }
        let r = view.page(f.reference);
        let _ = writeln!(
            s,
            "<path d=\"M{x0:.1} {y:.1}L{x1:.1} {y:.1}M{x:.1} {y0:.1}L{x:.1} {y1:.1}\" stroke=\"{colour}\" stroke-width=\"2\"/>\
<text x=\"{tx:.1}\" y=\"{ty:.1}\" font-size=\"13\" font-family=\"sans-serif\" fill=\"{colour}\">{name} ({role})</text>",
            x0 = r[0] - 7.0,
            x1 = r[0] + 7.0,
            x = r[0],
            y = r[1],
            y0 = r[1] - 7.0,
            y1 = r[1] + 7.0,
            tx = r[0] + 9.0,
            ty = r[1] - 9.0,
            name = esc(&f.name),
            role = if f.role == crate::input::spec::Role::Motion { "mount" } else { "force" },
        );
    }
    s.push_str("</svg>\n");
    s
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
        "The mesh's outline (isometric view, z up), each flange's slave nodes and its reference point".to_string(),
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
