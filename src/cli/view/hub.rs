//! What every open page is sent: takes each rendered frame (and the scene message that goes
//! with it) from the session and gives the connected pages binary frame updates — only the
//! rectangle where the 8-bit RGBA frame changed since the last one, or the whole frame to a
//! page that just connected — plus JSON text messages, in the order they were published.

use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex};

use super::lock;

/// Bytes before the pixels of a frame message: seven little-endian u32 — kind (1), canvas
/// width, canvas height, then the rectangle's x, y, width and height.
pub const FRAME_HEADER: usize = 28;

/// One message to a page.
#[derive(Clone, Debug)]
pub enum Outgoing {
    Binary(Arc<Vec<u8>>),
    Text(Arc<String>),
}

struct Client {
    id: u64,
    tx: Sender<Outgoing>,
    /// Whether this page shows the mesh overlay (its scene messages carry the meshes).
    mesh: bool,
}

/// A scene message in its two forms: without and with the placed meshes.
pub struct SceneText {
    pub plain: String,
    pub with_mesh: Option<String>,
}

#[derive(Default)]
struct State {
    clients: Vec<Client>,
    next_id: u64,
    /// The last published frame: width, height and RGBA8 bytes.
    frame: Option<(u32, u32, Vec<u8>)>,
    scene: Option<(Arc<String>, Option<Arc<String>>)>,
}

/// The pages connected to one session.
#[derive(Default)]
pub struct Hub {
    state: Mutex<State>,
}

impl Hub {
    /// Registers a page; it is sent the whole last frame and scene message first.
    pub fn connect(&self, tx: Sender<Outgoing>) -> u64 {
        let mut state = lock(&self.state);
        state.next_id += 1;
        let id = state.next_id;
        if let Some((w, h, rgba)) = &state.frame {
            let message = frame_message(*w, *h, rgba, [0, 0, *w, *h]);
            let _ = tx.send(Outgoing::Binary(Arc::new(message)));
        }
        if let Some((plain, _)) = &state.scene {
            let _ = tx.send(Outgoing::Text(plain.clone()));
        }
        state.clients.push(Client {
            id,
            tx,
            mesh: false,
        });
        id
    }

    pub fn disconnect(&self, id: u64) {
        lock(&self.state).clients.retain(|c| c.id != id);
    }

    /// Whether any page wants the meshes (so the session builds that form).
    pub fn wants_mesh(&self) -> bool {
        lock(&self.state).clients.iter().any(|c| c.mesh)
    }

    pub fn set_mesh(&self, id: u64, on: bool) {
        let mut state = lock(&self.state);
        if let Some(c) = state.clients.iter_mut().find(|c| c.id == id) {
            c.mesh = on;
        }
    }

    /// Sends every page what changed in `rgba` (a `width`×`height` RGBA8 frame), then `scene`.
    pub fn publish(&self, width: u32, height: u32, rgba: Vec<u8>, scene: SceneText) {
        let mut state = lock(&self.state);
        let rect = match &state.frame {
            Some((w, h, last)) if *w == width && *h == height => changed_rect(width, last, &rgba),
            _ => Some([0, 0, width, height]),
        };
        let rect = rect.unwrap_or([0, 0, 0, 0]);
        let frame = Arc::new(frame_message(width, height, &rgba, rect));
        let plain = Arc::new(scene.plain);
        let with_mesh = scene.with_mesh.map(Arc::new);
        state.clients.retain(|c| {
            let text = match (&with_mesh, c.mesh) {
                (Some(m), true) => m.clone(),
                _ => plain.clone(),
            };
            c.tx.send(Outgoing::Binary(frame.clone())).is_ok()
                && c.tx.send(Outgoing::Text(text)).is_ok()
        });
        state.frame = Some((width, height, rgba));
        state.scene = Some((plain, with_mesh));
    }

    /// Sends a text message to every page.
    pub fn broadcast(&self, text: String) {
        let text = Arc::new(text);
        lock(&self.state)
            .clients
            .retain(|c| c.tx.send(Outgoing::Text(text.clone())).is_ok());
    }
}

/// A channel for one page's messages.
pub fn channel() -> (Sender<Outgoing>, Receiver<Outgoing>) {
    std::sync::mpsc::channel()
}

/// The smallest rectangle `[x, y, w, h]` holding every pixel that differs, if any does.
pub fn changed_rect(width: u32, old: &[u8], new: &[u8]) -> Option<[u32; 4]> {
    let row = width as usize * 4;
    let rows: Vec<usize> = (0..new.len() / row.max(1))
        .filter(|&y| old[y * row..(y + 1) * row] != new[y * row..(y + 1) * row])
        .collect();
    let (&top, &bottom) = (rows.first()?, rows.last()?);
    let (mut left, mut right) = (width as usize, 0);
    for y in top..=bottom {
        let (a, b) = (&old[y * row..(y + 1) * row], &new[y * row..(y + 1) * row]);
        let differs = |x: &usize| a[x * 4..x * 4 + 4] != b[x * 4..x * 4 + 4];
        if let Some(x) = (0..left).find(differs) {
            left = x;
        }
        if let Some(x) = (right..width as usize).rev().find(differs) {
            right = x;
        }
    }
    Some([
        left as u32,
        top as u32,
        (right - left + 1) as u32,
        (bottom - top + 1) as u32,
    ])
}

/// The binary frame message for `rect` of the `width`×`height` frame `rgba`.
pub fn frame_message(width: u32, height: u32, rgba: &[u8], rect: [u32; 4]) -> Vec<u8> {
    let [x, y, w, h] = rect;
    let mut out = Vec::with_capacity(FRAME_HEADER + (w * h * 4) as usize);
    for v in [1, width, height, x, y, w, h] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let row = width as usize * 4;
    for j in y..y + h {
        let start = j as usize * row + x as usize * 4;
        out.extend_from_slice(&rgba[start..start + w as usize * 4]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_rect_bounds_every_difference() {
        let old = vec![0u8; 5 * 4 * 4];
        let mut new = old.clone();
        assert_eq!(changed_rect(5, &old, &new), None);
        new[(5 + 3) * 4] = 9; // (3, 1)
        new[(2 * 5 + 1) * 4 + 2] = 9; // (1, 2)
        assert_eq!(changed_rect(5, &old, &new), Some([1, 1, 3, 2]));
    }

    #[test]
    fn frame_message_carries_the_rectangle_rows() {
        let rgba: Vec<u8> = (0..3 * 2 * 4).map(|v| v as u8).collect();
        let m = frame_message(3, 2, &rgba, [1, 1, 2, 1]);
        assert_eq!(m.len(), FRAME_HEADER + 8);
        assert_eq!(&m[FRAME_HEADER..], &rgba[16..24]);
        assert_eq!(u32::from_le_bytes(m[4..8].try_into().unwrap()), 3);
    }
}
