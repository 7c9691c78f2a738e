//! The reader of binary MSH 4.1 files (see "Binary files" in the parent
//! module).

use super::builder::MeshBuilder;
use super::{Loc, Res, count_at, error, ints_of, physical_name};
use crate::import::{ImportError, ImportedMesh};
use std::path::Path;

/// Whether the file starts with a `$MeshFormat` section of file-type 1.
/// Anything else goes to the ASCII reader, which reports what is wrong.
pub(super) fn is_binary(bytes: &[u8]) -> bool {
    let mut r = Bin { path: Path::new(""), b: bytes, pos: 0 };
    matches!(r.line(), Some((_, l)) if l == b"$MeshFormat")
        && r.line().is_some_and(|(_, l)| {
            let t = ascii_tokens(l);
            t.len() == 3 && t.get(1) == Some(&&b"1"[..])
        })
}

/// ASCII-whitespace separated tokens of a line of bytes.
fn ascii_tokens(l: &[u8]) -> Vec<&[u8]> {
    l.split(|c| c.is_ascii_whitespace()).filter(|t| !t.is_empty()).collect()
}

/// A line of a binary file for a message: lossy UTF-8, escaped, at most
/// 40 characters.
fn shown(l: &[u8]) -> String {
    let s = String::from_utf8_lossy(l);
    let mut out: String = s.chars().take(40).flat_map(char::escape_debug).collect();
    if s.chars().nth(40).is_some() {
        out.push_str("...");
    }
    out
}

/// Cursor over the bytes of a binary MSH file. Every read is bounds
/// checked; running out of bytes is an "unexpected end of file" error.
struct Bin<'a> {
    path: &'a Path,
    b: &'a [u8],
    pos: usize,
}

impl<'a> Bin<'a> {
    fn err(&self, at: usize, msg: impl Into<String>) -> ImportError {
        error(self.path, Loc::Byte(at), msg)
    }

    fn eof(&self, section: &str, what: &str) -> ImportError {
        self.err(
            self.pos,
            format!(
                "unexpected end of file in ${section}: expected {what}, {} bytes left",
                self.b.len().saturating_sub(self.pos)
            ),
        )
    }

    /// The next `n` bytes (`what`, in `$section`).
    fn take(&mut self, n: usize, section: &str, what: &str) -> Res<&'a [u8]> {
        let b = self.b;
        match self.pos.checked_add(n).and_then(|end| b.get(self.pos..end)) {
            Some(s) => {
                self.pos += n;
                Ok(s)
            }
            None => Err(self.eof(section, &format!("{what} ({n} bytes)"))),
        }
    }

    fn array<const N: usize>(&mut self, section: &str, what: &str) -> Res<[u8; N]> {
        let at = self.pos;
        let s = self.take(N, section, what)?;
        <[u8; N]>::try_from(s).map_err(|_| self.err(at, format!("cannot read {what}")))
    }

    /// An `int` (i32).
    fn int(&mut self, section: &str, what: &str) -> Res<i32> {
        Ok(i32::from_le_bytes(self.array(section, what)?))
    }

    /// A `size_t` (u64, data-size 8).
    fn size(&mut self, section: &str, what: &str) -> Res<u64> {
        Ok(u64::from_le_bytes(self.array(section, what)?))
    }

    /// A `double` (f64).
    fn double(&mut self, section: &str, what: &str) -> Res<f64> {
        Ok(f64::from_le_bytes(self.array(section, what)?))
    }

    /// A `size_t` count.
    fn count(&mut self, section: &str, what: &str) -> Res<usize> {
        let at = self.pos;
        let v = self.size(section, what)?;
        usize::try_from(v).map_err(|_| self.err(at, format!("{what} {v} is too large")))
    }

    /// Skips `count` values of `width` bytes.
    fn skip(&mut self, count: usize, width: usize, section: &str, what: &str) -> Res<()> {
        match count.checked_mul(width) {
            Some(n) => self.take(n, section, what).map(|_| ()),
            None => Err(self.eof(section, &format!("{count} {what}"))),
        }
    }

    /// Skips ASCII whitespace, then returns the offset and the bytes (right
    /// trimmed) of the line up to the next `\n`, which is consumed; `None`
    /// at the end of the file.
    fn line(&mut self) -> Option<(usize, &'a [u8])> {
        let b = self.b;
        let rest = b.get(self.pos..)?;
        let Some(skip) = rest.iter().position(|c| !c.is_ascii_whitespace()) else {
            self.pos = b.len();
            return None;
        };
        let start = self.pos + skip;
        let rest = b.get(start..)?;
        let len = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
        self.pos = start + len + usize::from(len < rest.len());
        Some((start, rest.get(..len)?.trim_ascii_end()))
    }

    /// The next line, which must exist, in `$section`.
    fn ascii_line(&mut self, section: &str, what: &str) -> Res<(usize, &'a [u8])> {
        self.line().ok_or_else(|| self.eof(section, what))
    }

    /// Expects the line `$End<section>`.
    fn expect_end(&mut self, section: &str) -> Res<()> {
        let end = format!("$End{section}");
        let (at, l) = self.ascii_line(section, &end)?;
        if l != end.as_bytes() {
            return Err(self.err(at, format!("expected {end}, found '{}'", shown(l))));
        }
        Ok(())
    }

    /// Skips an unknown section (started at `at`) up to the line
    /// `$End<section>`.
    fn skip_section(&mut self, section: &str, at: usize) -> Res<()> {
        let end = format!("$End{section}");
        let pat = end.as_bytes();
        let b = self.b;
        let mut from = self.pos;
        while let Some(i) = b.get(from..).and_then(|rest| rest.windows(pat.len()).position(|w| w == pat)) {
            let start = from + i;
            let stop = start + pat.len();
            let line_start = start.checked_sub(1).and_then(|p| b.get(p)).is_none_or(|c| c.is_ascii_whitespace());
            let line_end = b.get(stop).is_none_or(|c| c.is_ascii_whitespace());
            if line_start && line_end {
                self.pos = stop;
                return Ok(());
            }
            from = start + 1;
        }
        Err(self.err(at, format!("section ${section} is not terminated by {end}")))
    }
}

/// The sections of the file, each read after its header line (at byte `at`).
impl Bin<'_> {
    /// `$PhysicalNames`: the names of the physical groups (ASCII lines in a binary file too).
    fn physical_names(&mut self, mb: &mut MeshBuilder<'_>) -> Res<()> {
        const S: &str = "PhysicalNames";
        let (at, l) = self.ascii_line(S, "the number of physical names")?;
        let t = String::from_utf8_lossy(l);
        let t: Vec<&str> = t.split_whitespace().collect();
        let c = ints_of(self.path, Loc::Byte(at), &t, 1, "$PhysicalNames count")?;
        for _ in 0..count_at(self.path, Loc::Byte(at), c[0], "count")? {
            let (at, l) = self.ascii_line(S, "a physical name line")?;
            let (key, name) = physical_name(self.path, Loc::Byte(at), &String::from_utf8_lossy(l))?;
            mb.physical_names.insert(key, name);
        }
        self.expect_end(S)?;
        Ok(())
    }

    /// `$Entities`: the physical groups of every point, curve, surface and volume.
    fn entities(&mut self, mb: &mut MeshBuilder<'_>) -> Res<()> {
        const S: &str = "Entities";
        let mut counts = [0usize; 4];
        for (dim, c) in counts.iter_mut().enumerate() {
            *c = self.count(S, &format!("the number of {dim}D entities"))?;
        }
        for (dim, &c) in (0i64..).zip(&counts) {
            for _ in 0..c {
                let tag = self.int(S, &format!("{dim}D entity tag"))?;
                // point: x y z; others: bounding box
                self.skip(if dim == 0 { 3 } else { 6 }, 8, S, "entity coordinates")?;
                let np = self.count(S, "the number of physical tags of an entity")?;
                let mut phys = Vec::new();
                for _ in 0..np {
                    phys.push(i64::from(self.int(S, "physical tag")?).abs());
                }
                if dim > 0 {
                    let nb = self.count(S, "the number of bounding entities")?;
                    self.skip(nb, 4, S, "bounding entity tags")?;
                }
                mb.entity_physicals.insert((dim, i64::from(tag)), phys);
            }
        }
        self.expect_end(S)?;
        mb.have_entities = true;
        Ok(())
    }

    /// `$Nodes`: blocks of node tags, then their coordinates.
    fn nodes(&mut self, at: usize, mb: &mut MeshBuilder<'_>) -> Res<()> {
        const S: &str = "Nodes";
        mb.begin_nodes(Loc::Byte(at))?;
        let header = Loc::Byte(self.pos);
        let blocks = self.count(S, "the number of node blocks")?;
        let total = self.count(S, "the number of nodes")?;
        self.skip(2, 8, S, "the min/max node tags")?;
        for _ in 0..blocks {
            let bat = self.pos;
            let dim = self.int(S, "node block entity dimension")?;
            self.int(S, "node block entity tag")?;
            let parametric = self.int(S, "node block parametric flag")? != 0;
            let nb = self.count(S, "the number of nodes in a block")?;
            if !(0..=3).contains(&dim) {
                return Err(self.err(bat, format!("invalid node block entity dimension {dim}")));
            }
            // parametric coordinates: u (curves), u v (surfaces), u v w (volumes)
            let extra = if parametric { dim as usize } else { 0 };
            let mut tags = Vec::with_capacity(nb.min(self.b.len() / 8));
            for _ in 0..nb {
                let at = self.pos;
                let tag = self.size(S, "node tag")?;
                mb.node_tag(Loc::Byte(at), tag)?;
                tags.push(tag);
            }
            for &tag in &tags {
                let at = self.pos;
                let mut x = [0.0; 3];
                for v in &mut x {
                    *v = self.double(S, "node coordinate")?;
                }
                if let Some(v) = x.iter().find(|v| !v.is_finite()) {
                    return Err(self.err(at, format!("coordinates of node {tag}: {v} is not a finite number")));
                }
                self.skip(extra, 8, S, "parametric node coordinates")?;
                mb.push_node(tag, x);
            }
        }
        mb.end_nodes(header, total)?;
        self.expect_end(S)?;
        Ok(())
    }

    /// `$Elements`: blocks of one element type, each element its tag and node tags.
    fn elements(&mut self, at: usize, mb: &mut MeshBuilder<'_>) -> Res<()> {
        const S: &str = "Elements";
        mb.begin_elements(Loc::Byte(at))?;
        let header = Loc::Byte(self.pos);
        let blocks = self.count(S, "the number of element blocks")?;
        let total = self.count(S, "the number of elements")?;
        self.skip(2, 8, S, "the min/max element tags")?;
        let mut seen = 0usize;
        for _ in 0..blocks {
            let bat = Loc::Byte(self.pos);
            let dim = self.int(S, "element block entity dimension")?;
            let etag = self.int(S, "element block entity tag")?;
            let etype = self.int(S, "element block element type")?;
            let ne = self.count(S, "the number of elements in a block")?;
            let block = mb.element_block(bat, i64::from(dim), i64::from(etag), i64::from(etype))?;
            let Some((_, nn, _)) = block.info else {
                return Err(mb.err(
                    bat,
                    format!(
                        "unknown element type {etype} in a {dim}D block: its node count is needed to read a binary file"
                    ),
                ));
            };
            for _ in 0..ne {
                let at = self.pos;
                let tag = self.size(S, "element tag")?;
                mb.element_tag(Loc::Byte(at), tag)?;
                let mut nodes = Vec::with_capacity(nn);
                for _ in 0..nn {
                    let at = self.pos;
                    let id = self.size(S, "element node tag")?;
                    nodes.push(mb.node_ref(Loc::Byte(at), tag, id)?);
                }
                mb.push_element(&block, tag, nodes);
            }
            seen = seen.saturating_add(ne);
        }
        mb.end_elements(header, total, seen)?;
        self.expect_end(S)?;
        Ok(())
    }
}

/// Parses a binary MSH 4.1 file (see the module documentation).
pub(super) fn parse_binary(bytes: &[u8], path: &Path) -> Res<ImportedMesh> {
    let mut r = Bin { path, b: bytes, pos: 0 };
    let mut mb = MeshBuilder::new(path);
    let mut have_format = false;
    while let Some((at, header)) = r.line() {
        let Some(section) = header.strip_prefix(b"$") else {
            return Err(r.err(at, format!("expected a section header ($Name), found '{}'", shown(header))));
        };
        let section = String::from_utf8_lossy(section).into_owned();
        if !have_format && section != "MeshFormat" {
            return Err(r.err(at, format!("expected $MeshFormat before ${section}")));
        }
        match section.as_str() {
            "MeshFormat" => {
                binary_mesh_format(&mut r)?;
                have_format = true;
            }
            "PhysicalNames" => r.physical_names(&mut mb)?,
            "Entities" => r.entities(&mut mb)?,
            "PartitionedEntities" => {
                return Err(r.err(at, "partitioned .msh files are not supported"));
            }
            "Nodes" => r.nodes(at, &mut mb)?,
            "Elements" => r.elements(at, &mut mb)?,
            _ => r.skip_section(&section, at)?,
        }
    }
    mb.finish(Loc::Byte(bytes.len()))
}

/// The rest of a binary file's `$MeshFormat` section, after its header.
fn binary_mesh_format(r: &mut Bin) -> Res<()> {
    const S: &str = "MeshFormat";
    let (at, l) = r.ascii_line(S, "'version file-type data-size'")?;
    let t = ascii_tokens(l);
    let text = |i: usize| t.get(i).map(|s| String::from_utf8_lossy(s)).unwrap_or_default();
    if t.len() != 3 {
        return Err(r.err(at, "$MeshFormat: expected 'version file-type data-size'"));
    }
    if text(1) != "1" {
        return Err(r.err(at, format!("$MeshFormat: file-type {} in a binary file", text(1))));
    }
    if text(0) != "4.1" {
        return Err(r.err(
            at,
            format!(
                "MSH version {} not supported: only 4.1, ASCII or binary (in Gmsh: Mesh.MshFileVersion = 4.1, or -format msh41)",
                text(0)
            ),
        ));
    }
    if text(2) != "8" {
        return Err(r.err(
            at,
            format!(
                "binary .msh with data-size {} not supported: only 8 (8-byte size_t, as written by 64-bit Gmsh)",
                text(2)
            ),
        ));
    }
    let at = r.pos;
    let one: [u8; 4] = r.array(S, "the endianness check (binary int 1)")?;
    if one != 1i32.to_le_bytes() {
        return Err(r.err(
            at,
            if one == 1i32.to_be_bytes() {
                "byte-swapped binary .msh (written on a big-endian machine) not supported: the endianness check int is 1 in big-endian byte order; save as ASCII".to_string()
            } else {
                format!(
                    "endianness check: expected the binary int 1, found bytes {one:02x?}"
                )
            },
        ));
    }
    r.expect_end(S)
}

#[cfg(test)]
mod tests {
    use super::super::test_data::{CUBE, FIXTURES};
    use super::super::{parse_msh, parse_msh_bytes};
    use super::*;

    /// Builds binary files by hand.
    #[derive(Default)]
    struct W {
        b: Vec<u8>,
        /// Offset recorded by [`W::mark`].
        mark: usize,
    }

    impl W {
        fn s(&mut self, s: &str) -> &mut Self {
            self.b.extend_from_slice(s.as_bytes());
            self
        }
        fn raw(&mut self, b: &[u8]) -> &mut Self {
            self.b.extend_from_slice(b);
            self
        }
        fn i(&mut self, v: i32) -> &mut Self {
            self.raw(&v.to_le_bytes())
        }
        fn z(&mut self, v: u64) -> &mut Self {
            self.raw(&v.to_le_bytes())
        }
        fn d(&mut self, v: f64) -> &mut Self {
            self.raw(&v.to_le_bytes())
        }
        fn ds(&mut self, v: &[f64]) -> &mut Self {
            for &x in v {
                self.d(x);
            }
            self
        }
        fn mark(&mut self) -> &mut Self {
            self.mark = self.b.len();
            self
        }
    }

    /// Defects [`cube_bin`] can build in.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Defect {
        None,
        DuplicateNodeTag,
        NodeCount,
        NanCoordinate,
        UndefinedNode,
        UnknownType,
        Prism,
    }

    /// [`CUBE`] as a binary file, plus an unknown section with binary
    /// content; returns the file and the offset of the defect.
    fn cube_bin(defect: Defect) -> (Vec<u8>, usize) {
        let is = |d: Defect| defect == d;
        let mut w = W::default();
        w.s("$MeshFormat\n4.1 1 8\n").i(1).s("\n$EndMeshFormat\n");
        w.s("$PhysicalNames\n2\n2 1 \"fixed\"\n3 2 \"body\"\n$EndPhysicalNames\n");
        w.s("$Entities\n").z(0).z(0).z(2).z(1);
        for (tag, bbox, phys) in [(1, [0., 0., 0., 1., 1., 0.], 1), (2, [0., 0., 1., 1., 1., 1.], 3)] {
            w.i(tag);
            w.ds(&bbox);
            w.z(1).i(phys).z(0);
        }
        w.i(1);
        w.ds(&[0., 0., 0., 1., 1., 1.]);
        w.z(1).i(2).z(2).i(1).i(-2);
        w.s("\n$EndEntities\n");

        w.s("$Nodes\n");
        if is(Defect::NodeCount) {
            w.mark();
        }
        w.z(2).z(if is(Defect::NodeCount) { 9 } else { 8 }).z(1).z(8);
        w.i(3).i(1).i(0).z(4);
        for tag in 1..=4 {
            if tag == 4 && is(Defect::DuplicateNodeTag) {
                w.mark().z(3);
            } else {
                w.z(tag);
            }
        }
        for (k, p) in [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]].into_iter().enumerate() {
            if k == 2 && is(Defect::NanCoordinate) {
                w.mark().d(p[0]).d(f64::NAN).d(p[2]);
            } else {
                w.ds(&p);
            }
        }
        // surface 2, parametric: x y z u v
        w.i(2).i(2).i(1).z(4);
        for tag in 5..=8 {
            w.z(tag);
        }
        for p in [[0., 0., 1., 0., 0.], [1., 0., 1., 1., 0.], [1., 1., 1., 1., 1.], [0., 1., 1., 0., 1.]] {
            w.ds(&p);
        }
        w.s("\n$EndNodes\n$Comments\nanything $here\n$EndComments\n");
        // Binary junk with a newline, a '$' and a look-alike end marker.
        w.s("$Junk\n").raw(&[0, b'\n', b'$', 0xff, 0xfe]).s("\n$EndJunkX\n");
        w.z(u64::MAX).s("\n$EndJunk\n");

        w.s("$Elements\n").z(3).z(4).z(1).z(5);
        w.i(2).i(1).i(3).z(1);
        w.z(1).z(1).z(2).z(3).z(4);
        if is(Defect::UnknownType) {
            w.mark();
        }
        w.i(2).i(2).i(if is(Defect::UnknownType) { 99 } else { 2 }).z(2);
        w.z(2).z(5).z(6).z(7);
        w.z(3).z(6).z(7);
        if is(Defect::UndefinedNode) {
            w.mark().z(9);
        } else {
            w.z(8);
        }
        if is(Defect::Prism) {
            w.mark();
        }
        w.i(3).i(1).i(if is(Defect::Prism) { 6 } else { 5 }).z(1);
        w.z(5);
        for n in 1..=8 {
            w.z(n);
        }
        w.s("\n$EndElements\n");
        (w.b, w.mark)
    }

    #[test]
    fn hand_made_binary_cube_equals_the_ascii_cube() {
        let (bin, _) = cube_bin(Defect::None);
        let ascii = parse_msh(CUBE, Path::new("cube.msh")).unwrap();
        assert_eq!(parse_msh_bytes(&bin, Path::new("cube.msh")).unwrap(), ascii);
        // and the ASCII text through the bytes entry point
        assert_eq!(parse_msh_bytes(CUBE.as_bytes(), Path::new("cube.msh")).unwrap(), ascii);
    }

    /// Parses a defective binary file; the error must name the byte.
    fn check_bin(bytes: &[u8], byte: usize, parts: &[&str]) {
        let e = parse_msh_bytes(bytes, Path::new("bad.msh")).unwrap_err();
        assert_eq!(e.line, 0, "{e}");
        assert!(e.to_string().starts_with(&format!("bad.msh: byte {byte}: ")), "wrong location: {e}");
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
    }

    #[test]
    fn binary_errors_name_the_byte() {
        let (_, first_tag3) = {
            // offset of node tag 3 in the intact file: 8 bytes before tag 4
            let (_, dup) = cube_bin(Defect::DuplicateNodeTag);
            ((), dup - 8)
        };
        let cases = [
            (Defect::DuplicateNodeTag, vec![format!("duplicate node tag 3 (first at byte {first_tag3})")]),
            (Defect::NodeCount, vec!["announces 9 nodes but the blocks contain 8".to_string()]),
            (Defect::NanCoordinate, vec!["coordinates of node 3: NaN is not a finite number".to_string()]),
            (Defect::UndefinedNode, vec!["element 3 references undefined node 9".to_string()]),
            (Defect::UnknownType, vec!["unknown element type 99 in a 2D block".to_string()]),
            (Defect::Prism, vec!["unsupported 3D element type 6 (prism6)".to_string()]),
        ];
        for (defect, parts) in cases {
            let (bin, at) = cube_bin(defect);
            let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
            check_bin(&bin, at, &parts);
        }

        let (good, _) = cube_bin(Defect::None);
        let replaced = |from: &[u8], to: &[u8]| -> Vec<u8> {
            let i = good.windows(from.len()).position(|w| w == from).expect("pattern in the file");
            [&good[..i], to, &good[i + from.len()..]].concat()
        };
        // $MeshFormat: version, data size, endianness check
        check_bin(&replaced(b"4.1 1 8", b"4.1 1 4"), 12, &["data-size 4 not supported", "only 8"]);
        check_bin(&replaced(b"4.1 1 8", b"2.2 1 8"), 12, &["version 2.2"]);
        check_bin(&replaced(b"8\n\x01\0\0\0", b"8\n\0\0\0\x01"), 20, &["byte-swapped", "big-endian"]);
        check_bin(&replaced(b"8\n\x01\0\0\0", b"8\n\x02\0\0\0"), 20, &["endianness check", "[02, 00, 00, 00]"]);
        // section footers
        let at = good.windows(10).position(|w| w == b"$EndNodes\n").unwrap();
        check_bin(&replaced(b"$EndNodes\n", b"$EndNodez\n"), at, &["expected $EndNodes, found '$EndNodez'"]);
        let at = good.windows(6).position(|w| w == b"$Junk\n").unwrap();
        check_bin(&replaced(b"$EndJunk\n", b"$EndJunq\n"), at, &["section $Junk is not terminated by $EndJunk"]);
        // the ASCII text entry point refuses binary content clearly
        let text = String::from_utf8_lossy(&good);
        let e = parse_msh(&text, Path::new("bad.msh")).unwrap_err();
        assert_eq!(e.line, 2);
        assert!(e.message.contains("read_msh / parse_msh_bytes"), "{e}");
    }

    #[test]
    fn truncated_binary_files_are_errors_not_panics() {
        let (cube, _) = cube_bin(Defect::None);
        let files = FIXTURES.iter().map(|&(name, _, bin)| (name, bin)).chain([("cube", &cube[..])]);
        for (name, bin) in files {
            let path = Path::new("cut.msh");
            let full = parse_msh_bytes(bin, path).unwrap();
            for len in 0..bin.len() - 1 {
                if let Ok(m) = parse_msh_bytes(&bin[..len], path) {
                    panic!("{name}: the first {len} of {} bytes parse ({} nodes)", bin.len(), m.num_nodes());
                }
            }
            // Only the final newline missing: the file is complete.
            assert_eq!(parse_msh_bytes(&bin[..bin.len() - 1], path).unwrap(), full);
        }

        // Cuts inside the binary sections name the section and the byte.
        let (_, _, bin) = FIXTURES[3];
        for (section, into, what) in [
            ("Entities", 3, "the number of 0D entities"),
            // header: 4 size_t; block header: 3 int + 1 size_t; then tags
            ("Nodes", 32 + 20 + 3, "node tag"),
            ("Elements", 32 + 20 + 8 + 3, "element node tag"),
        ] {
            let header = format!("${section}\n");
            let start = bin.windows(header.len()).position(|w| w == header.as_bytes()).unwrap() + header.len();
            let cut = start + into;
            let e = parse_msh_bytes(&bin[..cut], Path::new("cut.msh")).unwrap_err();
            assert_eq!(e.line, 0);
            let msg = e.to_string();
            assert!(
                msg.starts_with("cut.msh: byte ")
                    && msg.contains(&format!("unexpected end of file in ${section}: expected {what}")),
                "{msg}"
            );
        }
    }
}
