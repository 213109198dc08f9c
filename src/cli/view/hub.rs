//! What every open page is sent: takes each rendered frame (and the scene message that goes
//! with it) from the session and gives the connected pages binary frame updates — only what
//! changed in the 8-bit RGBA frame since the last one (each row's run from its first to its
//! last changed pixel), or the whole frame to a page that just connected — plus JSON text
//! messages, in the order they were published.
//! Between two frames over the same background only the union of their drawn regions can
//! differ, so only that part is converted and compared.

use std::sync::mpsc::TrySendError;
use std::sync::Mutex;

use lapclone::pixels::{Canvas, CanvasPixels, PixelFormat, PixelRect};
use lapclone::render::DrawnRegion;
use tungstenite::{Bytes, Utf8Bytes};

use super::lock;
use super::wake::PageSender;

/// Bytes before the pixels of a frame message: seven little-endian u32 — kind ([`RECT`] or
/// [`RUNS`]), canvas width, canvas height, then the rectangle's x, y, width and height.
pub const FRAME_HEADER: usize = 28;

/// A frame message carrying its rectangle's rows whole.
pub const RECT: u32 = 1;

/// A frame message carrying, per row of its rectangle, the run from the row's first to its
/// last changed pixel: after the header, per row two u32 (the run's first column from the
/// rectangle's left, its length), then the runs' pixels one after the other.
pub const RUNS: u32 = 2;

/// What changed in a frame: the smallest rectangle holding every changed pixel and, per row
/// of it, `[first column from the rectangle's left, length]` of the run from the row's first
/// to its last changed pixel (`[0, 0]`: the row did not change).
#[derive(Debug, PartialEq)]
struct Changes {
    rect: [u32; 4],
    runs: Vec<[u32; 2]>,
}

/// One message to a page; cloning one for another page shares its bytes.
#[derive(Clone, Debug)]
pub enum Outgoing {
    Binary(Bytes),
    Text(Utf8Bytes),
}

/// Messages queued for one page: a page that stops reading would otherwise hold every frame
/// published since (a gigabyte a minute during a drag). A page whose queue fills is sent
/// nothing more until it has read the queue, then the whole frame as it is by then.
pub const PAGE_QUEUE: usize = 64;

struct Client {
    id: u64,
    tx: PageSender<Outgoing>,
    /// Whether this page's queue filled: it missed updates, so the next thing it is sent is
    /// the whole frame ([`Hub::catch_up`]).
    behind: bool,
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
    /// The last published frame.
    frame: Option<Published>,
    scene: Option<(Utf8Bytes, Option<Utf8Bytes>)>,
    /// The page whose preview edit came last: its gesture is the one on every page.
    previewer: Option<u64>,
}

/// The last published frame: its size, RGBA8 bytes and where it may differ from its
/// background.
struct Published {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
    region: Option<DrawnRegion>,
}

/// The pages connected to one session.
#[derive(Default)]
pub struct Hub {
    state: Mutex<State>,
}

impl Hub {
    /// Registers a page; it is sent the whole last frame and scene message first.
    pub fn connect(&self, tx: PageSender<Outgoing>) -> u64 {
        let mut state = lock(&self.state);
        state.next_id += 1;
        let id = state.next_id;
        for message in state.whole(false) {
            let _ = tx.try_send(message);
        }
        state.clients.push(Client {
            id,
            tx,
            mesh: false,
            behind: false,
        });
        id
    }

    /// Forgets page `id`; true when its gesture was the last previewed, which then ends
    /// with it (a closed page leaves no preview behind on the others).
    pub fn disconnect(&self, id: u64) -> bool {
        let mut state = lock(&self.state);
        state.clients.retain(|c| c.id != id);
        let previewed = state.previewer == Some(id);
        if previewed {
            state.previewer = None;
        }
        previewed
    }

    /// Page `id` has just previewed a gesture.
    pub fn set_previewer(&self, id: u64) {
        lock(&self.state).previewer = Some(id);
    }

    /// For page `id` once it has read its queue: if updates were dropped for it, queues the
    /// whole last frame and scene message, so it shows what every other page shows.
    pub fn catch_up(&self, id: u64) {
        let mut state = lock(&self.state);
        let behind = state.clients.iter().find(|c| c.id == id && c.behind);
        let Some(mesh) = behind.map(|c| c.mesh) else {
            return;
        };
        let messages = state.whole(mesh);
        if let Some(c) = state.clients.iter_mut().find(|c| c.id == id) {
            c.behind = !messages.into_iter().all(|m| c.tx.try_send(m).is_ok());
        }
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

    /// Sends every page what changed in `frame` (rounded to 8-bit RGBA) since the last one,
    /// then `scene`. `region` is where `frame` may differ from its background
    /// ([`Renderer::drawn_region`](lapclone::Renderer::drawn_region)).
    pub fn publish(&self, frame: &Canvas, region: Option<DrawnRegion>, scene: SceneText) {
        let mut state = lock(&self.state);
        let changes = state
            .frame
            .as_mut()
            .and_then(|last| last.update(frame, region));
        let message = match (changes, &state.frame) {
            (Some(Some(changes)), Some(last)) => runs_message(last, &changes),
            (Some(None), Some(last)) => frame_message(last.width, last.height, &last.rgba, [0; 4]),
            _ => {
                let (width, height) = (frame.width(), frame.height());
                let rgba = frame.to_rgba8_image().into_raw();
                let message = frame_message(width, height, &rgba, [0, 0, width, height]);
                state.frame = Some(Published {
                    width,
                    height,
                    rgba,
                    region,
                });
                message
            }
        };
        let frame = Bytes::from(message);
        let plain = Utf8Bytes::from(scene.plain);
        let with_mesh = scene.with_mesh.map(Utf8Bytes::from);
        state.clients.retain_mut(|c| {
            let text = match (&with_mesh, c.mesh) {
                (Some(m), true) => m.clone(),
                _ => plain.clone(),
            };
            c.offer(Outgoing::Binary(frame.clone())) && c.offer(Outgoing::Text(text))
        });
        state.scene = Some((plain, with_mesh));
    }

    /// Sends a text message to every page.
    pub fn broadcast(&self, text: String) {
        let text = Utf8Bytes::from(text);
        lock(&self.state)
            .clients
            .retain_mut(|c| c.offer(Outgoing::Text(text.clone())));
    }
}

impl State {
    /// The whole last frame and scene message (with the meshes for `mesh`), as a page that
    /// knows nothing yet is sent them.
    fn whole(&self, mesh: bool) -> Vec<Outgoing> {
        let mut messages = Vec::new();
        if let Some(Published {
            width: w,
            height: h,
            rgba,
            ..
        }) = &self.frame
        {
            let message = frame_message(*w, *h, rgba, [0, 0, *w, *h]);
            messages.push(Outgoing::Binary(message.into()));
        }
        if let Some((plain, with_mesh)) = &self.scene {
            let text = match (with_mesh, mesh) {
                (Some(m), true) => m,
                _ => plain,
            };
            messages.push(Outgoing::Text(text.clone()));
        }
        messages
    }
}

impl Client {
    /// Queues `message` unless the page is behind; marks it behind when its queue is full.
    /// False once the page is gone.
    fn offer(&mut self, message: Outgoing) -> bool {
        if self.behind {
            return true;
        }
        match self.tx.try_send(message) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.behind = true;
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        }
    }
}

impl Published {
    /// Takes in `frame` when it has this frame's size, comparing only the union of the two
    /// drawn regions when both are known over the same background, else the whole frame.
    /// Gives what changed (`None` inside: nothing did), or `None` when the size differs and
    /// the whole frame must be taken instead.
    fn update(&mut self, frame: &Canvas, region: Option<DrawnRegion>) -> Option<Option<Changes>> {
        if (frame.width(), frame.height()) != (self.width, self.height) {
            return None;
        }
        let union = compared_region(self.region, region, frame.bounds());
        self.region = region;
        let Some(union) = union else {
            return Some(None);
        };
        Some(self.take_rows(frame, union))
    }

    /// Copies `frame`'s pixels inside `union` into the kept frame; gives what changed
    /// (`None`: nothing did).
    fn take_rows(&mut self, frame: &Canvas, union: PixelRect) -> Option<Changes> {
        let (x0, w) = (union.x0 as usize, union.width());
        let row = self.width as usize * 4;
        // Rows are compared where they are: only the union's columns of each row. Each
        // changed row's run, as (row, first, last) in the union's pixels.
        let mut changed: Vec<[usize; 3]> = Vec::new();
        let mut converted: Vec<u8>;
        for y in union.y0 as usize..union.y1 as usize {
            let new_row = match frame.pixels() {
                CanvasPixels::Eight(p) => p[y * self.width as usize + x0..][..w].as_flattened(),
                CanvasPixels::Sixteen(_) => {
                    let (x, y) = (x0 as u32, y as u32);
                    converted = frame.samples_in(PixelFormat::RGBA8, x..x + w as u32, y..y + 1);
                    &converted[..]
                }
            };
            let old_row = &mut self.rgba[y * row + x0 * 4..][..w * 4];
            if *old_row == *new_row {
                continue;
            }
            // Pixel by pixel (one 32-bit compare each), not byte by byte.
            // invariant: both rows are whole RGBA pixels, so the casts cannot fail.
            let pixels = || {
                let old: &[[u8; 4]] = bytemuck::cast_slice(old_row);
                let new: &[[u8; 4]] = bytemuck::cast_slice(new_row);
                old.iter().zip(new)
            };
            // invariant: the rows differ, so a first and a last difference exist.
            let first = pixels().position(|(a, b)| a != b).expect("a difference");
            let last = pixels().rposition(|(a, b)| a != b).expect("a difference");
            changed.push([y, first, last]);
            old_row.copy_from_slice(new_row);
        }
        changes(&changed, x0)
    }
}

/// The rectangle and row runs of the changed rows' runs `[row, first, last]` (columns from
/// `x0`, rows ascending).
fn changes(changed: &[[usize; 3]], x0: usize) -> Option<Changes> {
    let (&[top, ..], &[bottom, ..]) = (changed.first()?, changed.last()?);
    let left = changed.iter().map(|c| c[1]).min()?;
    let right = changed.iter().map(|c| c[2]).max()?;
    let mut runs = vec![[0, 0]; bottom - top + 1];
    for &[y, first, last] in changed {
        runs[y - top] = [(first - left) as u32, (last - first + 1) as u32];
    }
    let rect = [
        (x0 + left) as u32,
        top as u32,
        (right - left + 1) as u32,
        runs.len() as u32,
    ];
    Some(Changes { rect, runs })
}

/// Where two frames can differ: the union of their drawn regions inside `whole` when both are
/// known over the same background (`None`: both drew nothing), else the whole frame.
fn compared_region(
    old: Option<DrawnRegion>,
    new: Option<DrawnRegion>,
    whole: PixelRect,
) -> Option<PixelRect> {
    match (old, new) {
        (Some(old), Some(new)) if old.background == new.background => [old.rect, new.rect]
            .into_iter()
            .map(|r| r.intersect(&whole))
            .filter(|r| !r.is_empty())
            .reduce(|a, b| a.union(&b)),
        _ => Some(whole),
    }
}

/// The binary frame message ([`RECT`]) for `rect` of the `width`×`height` frame `rgba`.
pub fn frame_message(width: u32, height: u32, rgba: &[u8], rect: [u32; 4]) -> Vec<u8> {
    let [x, y, w, h] = rect;
    let mut out = header(RECT, width, height, rect, (w * h * 4) as usize);
    let row = width as usize * 4;
    for j in y..y + h {
        let start = j as usize * row + x as usize * 4;
        out.extend_from_slice(&rgba[start..start + w as usize * 4]);
    }
    out
}

/// A frame message's header, with room for `body` more bytes.
fn header(kind: u32, width: u32, height: u32, [x, y, w, h]: [u32; 4], body: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(FRAME_HEADER + body);
    for v in [kind, width, height, x, y, w, h] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// The binary frame message ([`RUNS`]) for `changes` of the published frame `last`.
fn runs_message(last: &Published, changes: &Changes) -> Vec<u8> {
    let [x, y, ..] = changes.rect;
    let pixels: usize = changes.runs.iter().map(|r| r[1] as usize * 4).sum();
    let body = changes.runs.len() * 8 + pixels;
    let mut out = header(RUNS, last.width, last.height, changes.rect, body);
    for v in changes.runs.iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let row = last.width as usize * 4;
    for (j, &[first, length]) in (y as usize..).zip(&changes.runs) {
        let start = j * row + (x + first) as usize * 4;
        out.extend_from_slice(&last.rgba[start..start + length as usize * 4]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel() -> (
        PageSender<Outgoing>,
        crate::cli::view::wake::PageQueue<Outgoing>,
    ) {
        crate::cli::view::wake::page_channel(PAGE_QUEUE).unwrap()
    }

    fn canvas(pixels: &[(usize, [u8; 4])]) -> Canvas {
        let mut rgba = vec![[10, 20, 30, 255]; 6 * 5];
        for &(i, p) in pixels {
            rgba[i] = p;
        }
        Canvas::from_rgba8(6, 5, rgba).unwrap()
    }

    fn region(background: u64, x0: i32, y0: i32, x1: i32, y1: i32) -> Option<DrawnRegion> {
        let rect = PixelRect { x0, y0, x1, y1 };
        Some(DrawnRegion { background, rect })
    }

    fn scene() -> SceneText {
        SceneText {
            plain: "{}".into(),
            with_mesh: None,
        }
    }

    /// The rectangle of a frame message.
    fn rect_of(message: &Outgoing) -> [u32; 4] {
        let Outgoing::Binary(m) = message else {
            panic!("not a frame: {message:?}");
        };
        let word = |k: usize| u32::from_le_bytes(m[4 * k..4 * k + 4].try_into().unwrap());
        [word(3), word(4), word(5), word(6)]
    }

    #[test]
    fn updates_bound_the_changes_inside_the_drawn_regions() {
        let hub = Hub::default();
        let (tx, rx) = channel();
        hub.connect(tx);
        // A first frame goes whole; then only what changed inside old ∪ new drawn regions.
        hub.publish(
            &canvas(&[(7, [1, 2, 3, 4])]),
            region(1, 1, 1, 2, 2),
            scene(),
        );
        assert_eq!(rect_of(&rx.recv().unwrap()), [0, 0, 6, 5]);
        rx.recv().unwrap();
        // The pixel at (1, 1) is background again; (4, 3) and (3, 2) were drawn.
        let next = canvas(&[(6 * 3 + 4, [9, 9, 9, 9]), (6 * 2 + 3, [8, 8, 8, 8])]);
        hub.publish(&next, region(1, 3, 2, 5, 4), scene());
        assert_eq!(rect_of(&rx.recv().unwrap()), [1, 1, 4, 3]);
        rx.recv().unwrap();
        // The same frame again: nothing changed.
        hub.publish(&next, region(1, 3, 2, 5, 4), scene());
        assert_eq!(rect_of(&rx.recv().unwrap()), [0, 0, 0, 0]);
        rx.recv().unwrap();
        // Another background, or an unknown region: the whole frame is compared.
        let other = canvas(&[(0, [0, 0, 0, 0]), (6 * 3 + 4, [9, 9, 9, 9])]);
        hub.publish(&other, region(2, 4, 3, 5, 4), scene());
        assert_eq!(rect_of(&rx.recv().unwrap()), [0, 0, 4, 3]);
        rx.recv().unwrap();
        hub.publish(&canvas(&[]), None, scene());
        assert_eq!(rect_of(&rx.recv().unwrap()), [0, 0, 5, 4]);
        // A page that connects now is sent the frame last published, whole.
        let (tx, late) = channel();
        hub.connect(tx);
        let Outgoing::Binary(m) = late.recv().unwrap() else {
            panic!("no frame");
        };
        assert_eq!(&m[FRAME_HEADER..], canvas(&[]).samples(PixelFormat::RGBA8));
    }

    /// A page that stops reading is queued at most [`PAGE_QUEUE`] messages; once it reads
    /// them it is sent the whole frame as it is then. A page that reads misses nothing.
    #[test]
    fn a_page_that_stops_reading_holds_a_bounded_queue_then_catches_up() {
        let hub = Hub::default();
        let (tx, stuck) = channel();
        let stuck_id = hub.connect(tx);
        let (tx, reader) = channel();
        hub.connect(tx);
        let mut read = 0;
        let frames = 3 * PAGE_QUEUE;
        let mut last = canvas(&[]);
        for k in 0..frames {
            last = canvas(&[(k % 30, [k as u8, 0, 0, 255])]);
            hub.publish(&last, None, scene());
            read += reader.try_iter().count();
        }
        hub.catch_up(stuck_id); // its queue is still full: nothing more
        assert_eq!(read, 2 * frames, "the reading page missed updates");
        let queued: Vec<Outgoing> = stuck.try_iter().collect();
        assert_eq!(queued.len(), PAGE_QUEUE);
        hub.catch_up(stuck_id);
        let caught: Vec<Outgoing> = stuck.try_iter().collect();
        let [Outgoing::Binary(m), Outgoing::Text(_)] = &caught[..] else {
            panic!("not the whole frame and the scene after catching up: {caught:?}");
        };
        assert_eq!(&m[FRAME_HEADER..], last.samples(PixelFormat::RGBA8));
        hub.catch_up(stuck_id);
        assert_eq!(stuck.try_iter().count(), 0, "caught up twice");
    }

    /// The pixels a message carries, written into `frame` (6 px wide) as a page does.
    fn apply(message: &Outgoing, frame: &mut [[u8; 4]]) {
        let Outgoing::Binary(m) = message else {
            panic!("not a frame: {message:?}");
        };
        let word = |k: usize| u32::from_le_bytes(m[4 * k..4 * k + 4].try_into().unwrap()) as usize;
        let [x, y, w, h] = [3, 4, 5, 6].map(word);
        let mut at = FRAME_HEADER + if word(0) == RUNS as usize { 8 * h } else { 0 };
        for j in 0..h {
            let [first, length] = match word(0) as u32 {
                RUNS => [word(7 + 2 * j), word(8 + 2 * j)],
                _ => [0, w],
            };
            for (k, pixel) in m[at..at + 4 * length].chunks(4).enumerate() {
                frame[(y + j) * 6 + x + first + k].copy_from_slice(pixel);
            }
            at += 4 * length;
        }
        assert_eq!(at, m.len());
    }

    /// Row by row only the runs that changed go out, and a page applying them ends with the
    /// published frame; rows with nothing changed inside the rectangle carry no pixels.
    #[test]
    fn updates_carry_each_rows_changed_run() {
        let hub = Hub::default();
        let (tx, rx) = channel();
        hub.connect(tx);
        let first = canvas(&[]);
        hub.publish(&first, region(1, 0, 0, 6, 5), scene());
        let mut page = vec![[0u8; 4]; 30];
        apply(&rx.recv().unwrap(), &mut page);
        rx.recv().unwrap();
        // Row 1: columns 1 and 4 (the run spans 1..=4); row 2 unchanged; row 3: column 2.
        let changed = [
            (6 + 1, [1, 1, 1, 1]),
            (6 + 4, [2, 2, 2, 2]),
            (18 + 2, [3, 3, 3, 3]),
        ];
        let next = canvas(&changed);
        hub.publish(&next, region(1, 0, 0, 6, 5), scene());
        let message = rx.recv().unwrap();
        assert_eq!(rect_of(&message), [1, 1, 4, 3]);
        let Outgoing::Binary(m) = &message else {
            panic!("no frame");
        };
        // Header, three rows' runs, then 4 + 0 + 1 pixels.
        assert_eq!(m.len(), FRAME_HEADER + 3 * 8 + 5 * 4);
        apply(&message, &mut page);
        assert_eq!(page.as_flattened(), next.samples(PixelFormat::RGBA8));
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
