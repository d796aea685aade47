//! The known part of a map.
//!
//! Early on, a laser SLAM map of an unknown world is mostly unknown (−1): the hector map is a
//! fixed 1024² grid of which the robot has seen a few square metres. Costs only vary near
//! known obstacles, so the costmap transforms just the bounding box of the known cells plus a
//! margin, and the global planner searches little beyond it. Finding that box is a scan over
//! every cell, so it is written to vectorise.

/// A rectangle of cells: columns `x0 .. x0 + w`, rows `y0 .. y0 + h`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CellWindow {
    pub x0: usize,
    pub y0: usize,
    pub w: usize,
    pub h: usize,
}

impl CellWindow {
    pub fn contains(&self, ix: usize, iy: usize) -> bool {
        ix.wrapping_sub(self.x0) < self.w && iy.wrapping_sub(self.y0) < self.h
    }

    pub fn is_empty(&self) -> bool {
        self.w == 0 || self.h == 0
    }
}

/// Bounding box of the known cells, grown by `margin` cells and clipped to the grid.
pub(crate) fn known_window(cells: &[i8], width: usize, height: usize, margin: usize) -> CellWindow {
    let (mut x0, mut x1, mut y0, mut y1) = (usize::MAX, 0, usize::MAX, 0);
    for y in 0..height {
        let row = &cells[y * width..(y + 1) * width];
        if let Some(first) = first_known(row) {
            let last = last_known(row).unwrap_or(first);
            x0 = x0.min(first);
            x1 = x1.max(last + 1);
            y0 = y0.min(y);
            y1 = y + 1;
        }
    }
    if x0 == usize::MAX {
        return CellWindow::default();
    }
    let (x0, y0) = (x0.saturating_sub(margin), y0.saturating_sub(margin));
    let (x1, y1) = ((x1 + margin).min(width), (y1 + margin).min(height));
    CellWindow {
        x0,
        y0,
        w: x1 - x0,
        h: y1 - y0,
    }
}

/// Chunk size for scanning rows of a mostly unknown map: each chunk is tested without early
/// exit, which the compiler vectorises.
const SCAN_CHUNK: usize = 64;

fn chunk_known(chunk: &[i8]) -> bool {
    chunk.iter().fold(false, |any, &c| any | (c != -1))
}

/// Index of the first known (≠ −1) cell of a row.
fn first_known(row: &[i8]) -> Option<usize> {
    let chunk = row.chunks(SCAN_CHUNK).position(chunk_known)?;
    let start = chunk * SCAN_CHUNK;
    row[start..]
        .iter()
        .position(|&c| c != -1)
        .map(|i| start + i)
}

/// Index of the last known (≠ −1) cell of a row.
fn last_known(row: &[i8]) -> Option<usize> {
    let tail = row.len() % SCAN_CHUNK;
    if let Some(i) = row[row.len() - tail..].iter().rposition(|&c| c != -1) {
        return Some(row.len() - tail + i);
    }
    let chunk = row[..row.len() - tail]
        .chunks_exact(SCAN_CHUNK)
        .rposition(chunk_known)?;
    let start = chunk * SCAN_CHUNK;
    row[start..start + SCAN_CHUNK]
        .iter()
        .rposition(|&c| c != -1)
        .map(|i| start + i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_cell_scan_finds_row_extremes() {
        for len in [1usize, 63, 64, 65, 200] {
            for a in 0..len {
                for b in [a, (a + 70).min(len - 1), len - 1] {
                    let mut row = vec![-1i8; len];
                    row[a] = 0;
                    row[b] = 100;
                    assert_eq!(first_known(&row), Some(a), "len {len} a {a} b {b}");
                    assert_eq!(last_known(&row), Some(b), "len {len} a {a} b {b}");
                }
            }
            assert_eq!(first_known(&vec![-1i8; len]), None);
            assert_eq!(last_known(&vec![-1i8; len]), None);
        }
    }

    #[test]
    fn window_is_the_known_box_plus_margin_clipped_to_the_grid() {
        let (w, h) = (100, 50);
        let mut cells = vec![-1i8; w * h];
        cells[10 * w + 30] = 0;
        cells[20 * w + 60] = 100;
        let win = known_window(&cells, w, h, 5);
        assert_eq!(
            win,
            CellWindow {
                x0: 25,
                y0: 5,
                w: 41,
                h: 21
            }
        );
        let win = known_window(&cells, w, h, 40);
        assert_eq!(
            win,
            CellWindow {
                x0: 0,
                y0: 0,
                w: 100,
                h: 50
            }
        );
        assert!(known_window(&vec![-1i8; w * h], w, h, 5).is_empty());
    }
}
