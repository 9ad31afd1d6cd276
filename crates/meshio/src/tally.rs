//! Counts of the cells a tetrahedral reader skips, by type number, for the error that says what
//! a file without tetrahedra holds.

/// How many distinct types are counted apart; the rest are counted together.
const MAX_KINDS: usize = 16;

/// Skipped cells (or elements) by type, in order of first appearance.
///
/// A type number comes from the file, so a hostile file can give every cell a type of its own:
/// only the first [`MAX_KINDS`] types are kept apart, so that counting stays linear in the
/// number of cells and the message short.
#[derive(Debug, Default)]
pub(crate) struct TypeCounts {
    kinds: Vec<(i64, usize)>,
    /// Cells of the types past the first [`MAX_KINDS`].
    others: usize,
}

impl TypeCounts {
    /// Counts one cell of type `ty`.
    pub(crate) fn add(&mut self, ty: i64) {
        if let Some((_, n)) = self.kinds.iter_mut().find(|(t, _)| *t == ty) {
            *n += 1;
        } else if self.kinds.len() < MAX_KINDS {
            self.kinds.push((ty, 1));
        } else {
            self.others += 1;
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.kinds.is_empty()
    }

    /// "3 triangles (type 5), 1 vertices (type 1)", with `name` naming each type; `noun` is
    /// what the file holds (`"cells"`, `"elements"`).
    pub(crate) fn describe(&self, noun: &str, name: fn(i64) -> &'static str) -> String {
        if self.kinds.is_empty() {
            return format!("no {noun}");
        }
        let mut parts: Vec<String> = self
            .kinds
            .iter()
            .map(|&(ty, n)| format!("{n} {} (type {ty})", name(ty)))
            .collect();
        if self.others > 0 {
            parts.push(format!("{} {noun} of other types", self.others));
        }
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn many_types_are_counted_together_past_the_first() {
        let mut t = TypeCounts::default();
        assert_eq!(t.describe("cells", |_| "x"), "no cells");
        t.add(5);
        t.add(5);
        t.add(1);
        assert_eq!(t.describe("cells", |_| "x"), "2 x (type 5), 1 x (type 1)");
        for ty in 100..100_000 {
            t.add(ty);
        }
        assert_eq!(t.kinds.len(), MAX_KINDS);
        let s = t.describe("cells", |_| "x");
        assert!(
            s.ends_with(&format!("{} cells of other types", 100_000 - 100 - 14)),
            "{s}"
        );
        assert!(s.len() < 400, "{s}");
    }
}
