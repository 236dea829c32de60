//! Rollback netcode with GGRS (the `ggrs` crate) driving a carom world.
//!
//! GGRS runs the game a few frames ahead on predicted inputs, and when the real inputs
//! arrive and differ it asks the game to load an older state and simulate forward again.
//! carom gives it what that needs: `World::snapshot` / `World::restore` to a byte
//! buffer, bit-identical stepping, and `World::checksum` to compare states.
//!
//! Both players' inputs are scripted (a fixed-seed pattern), so a plain run without GGRS
//! gives the reference checksum of every frame. Then:
//! 1. A `SyncTestSession`: every frame GGRS rolls back 7 frames and resimulates them,
//!    comparing carom's checksums with the first run's. This program also checks that
//!    every restored world has the checksum it was saved with, and that every frame's
//!    state equals the reference.
//! 2. Two `P2PSession` peers in one process over an in-memory network that drops 10 % of
//!    the packets and delays the rest by 1 to 5 ticks (reordering some), from a fixed
//!    seed; GGRS's desync detection is on. Each peer runs ahead on predicted inputs and
//!    rolls back when the other's arrive. Every confirmed frame of both peers must equal
//!    the reference. (GGRS's handshake and resends run on the wall clock, so how many
//!    rollbacks happen varies from run to run; the confirmed checksums never do.)
//!
//! Exits non-zero when a checksum disagrees. Run with
//! `cargo run --release --example rollback_ggrs`; add `-- --desync` to nudge one ball on
//! peer 1 only at frame 100 and watch GGRS report the desync (and the run fail).
//! `tests/rollback_ggrs.rs` runs both.

use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::error::Error;
use std::rc::Rc;

use carom::rng::SplitMix64;
use carom::{BodyDesc, BodyHandle, Shape, Vec3, World};
use ggrs::{
    Config, DesyncDetection, Frame, GgrsError, GgrsEvent, GgrsRequest, InputStatus, Message,
    NonBlockingSocket, P2PSession, PlayerType, SessionBuilder, SessionState,
};

/// The game's world: 2 players and 24 crates, about 150 KB (fine on the stack, boxed
/// anyway so moving a `Game` is cheap).
type GameWorld = World<'static, 32, 128>;

/// Input bits of one player for one frame.
const LEFT: u8 = 1;
const RIGHT: u8 = 2;
const FORWARD: u8 = 4;
const JUMP: u8 = 8;

/// GGRS's view of the game: a `u8` of input bits per player, a carom snapshot as the
/// saved state, and peers addressed by a number.
struct GgrsConfig;

impl Config for GgrsConfig {
    type Input = u8;
    type InputPredictor = ggrs::PredictRepeatLast;
    type State = Saved;
    type Address = u8;
}

/// A saved frame: the snapshot bytes and the checksum of the world they came from.
#[derive(Clone)]
struct Saved {
    bytes: Vec<u8>,
    checksum: u64,
}

/// One peer's copy of the game.
struct Game {
    world: Box<GameWorld>,
    players: [BodyHandle; 2],
    /// The checksum of the state saved for each frame, last save wins: after GGRS
    /// resimulates a frame with corrected inputs, its entry holds the corrected state.
    history: BTreeMap<Frame, u64>,
    /// Rollbacks (load requests) served.
    loads: u32,
    /// A step at which to nudge a ball: makes this copy diverge, to show detection.
    sabotage_at: Option<u64>,
}

impl Game {
    fn new() -> Result<Game, carom::Error> {
        let mut world: Box<GameWorld> = Box::new(World::new());
        world.add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(20.0, 0.5, 20.0))?)
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )?;
        let crate_shape = Shape::cuboid(Vec3::splat(0.4))?;
        for i in 0..24 {
            let (x, y, z) = ((i % 4) as f32, (i / 8) as f32, ((i / 4) % 2) as f32);
            world.add(
                BodyDesc::dynamic(crate_shape)
                    .position(Vec3::new(0.85 * x - 1.3, 0.4 + 0.8 * y, 0.85 * z))
                    .density(200.0),
            )?;
        }
        let ball = Shape::sphere(0.5)?;
        let players = [
            world.add(BodyDesc::dynamic(ball).position(Vec3::new(-6.0, 0.5, 0.0)))?,
            world.add(BodyDesc::dynamic(ball).position(Vec3::new(6.0, 0.5, 0.0)))?,
        ];
        Ok(Game {
            world,
            players,
            history: BTreeMap::new(),
            loads: 0,
            sabotage_at: None,
        })
    }

    /// One frame: each player's input becomes a force on their ball, then one step.
    fn advance(&mut self, inputs: &[(u8, InputStatus)]) -> Result<(), carom::Error> {
        for (&player, &(bits, _status)) in self.players.iter().zip(inputs) {
            let mut f = Vec3::ZERO;
            let push = 6000.0; // N, on a 524 kg ball
            if bits & LEFT != 0 {
                f.x -= push;
            }
            if bits & RIGHT != 0 {
                f.x += push;
            }
            if bits & FORWARD != 0 {
                f.z += push;
            }
            if bits & JUMP != 0 && self.world.body(player)?.position().y < 0.6 {
                f.y += 20.0 * push;
            }
            self.world.apply_force(player, f)?;
        }
        if self.sabotage_at == Some(self.world.step_count()) {
            self.world
                .apply_force(self.players[0], Vec3::new(0.0, 0.0, 1.0))?;
        }
        self.world.step();
        Ok(())
    }

    /// Serve GGRS's requests, in order.
    fn handle(&mut self, requests: Vec<GgrsRequest<GgrsConfig>>) -> Result<(), Box<dyn Error>> {
        for request in requests {
            match request {
                GgrsRequest::SaveGameState { cell, frame } => {
                    let mut bytes = vec![0u8; GameWorld::max_snapshot_len()];
                    let n = self.world.snapshot(&mut bytes)?;
                    bytes.truncate(n);
                    let checksum = self.world.checksum();
                    self.history.insert(frame, checksum);
                    cell.save(
                        frame,
                        Some(Saved { bytes, checksum }),
                        Some(u128::from(checksum)),
                    );
                }
                GgrsRequest::LoadGameState { cell, frame } => {
                    let saved = cell
                        .load()
                        .ok_or("GGRS asked to load a frame never saved")?;
                    self.world.restore(&saved.bytes)?;
                    if self.world.checksum() != saved.checksum {
                        return Err(format!("frame {frame}: the restored world differs").into());
                    }
                    self.loads += 1;
                }
                GgrsRequest::AdvanceFrame { inputs } => self.advance(&inputs)?,
            }
        }
        Ok(())
    }
}

/// The scripted input of `player` for `frame`: a fixed-seed pattern that changes every
/// 20 frames or so, so GGRS's "repeat the last input" prediction is sometimes wrong.
fn scripted_input(player: usize, frame: u32) -> u8 {
    let mut rng = SplitMix64::new(0xC0FFEE ^ ((player as u64) << 40) ^ u64::from(frame / 20));
    (rng.next_u64() & 0x0F) as u8
}

/// Both players' scripted inputs for `frame`, as GGRS would pass them.
fn scripted_inputs(frame: u32) -> [(u8, InputStatus); 2] {
    [0, 1].map(|player| (scripted_input(player, frame), InputStatus::Confirmed))
}

/// The checksum at the start of every frame `0..=frames` of a plain run, no GGRS.
fn reference(frames: u32) -> Result<Vec<u64>, carom::Error> {
    let mut game = Game::new()?;
    let mut sums = vec![game.world.checksum()];
    for frame in 0..frames {
        game.advance(&scripted_inputs(frame))?;
        sums.push(game.world.checksum());
    }
    Ok(sums)
}

/// Check a game's saved checksums of frames `0..=last` against the reference.
fn check(who: &str, game: &Game, reference: &[u64], last: Frame) -> Result<(), Box<dyn Error>> {
    for frame in 0..=last {
        let saved = game.history.get(&frame).copied();
        let expected = usize::try_from(frame)
            .ok()
            .and_then(|f| reference.get(f))
            .copied();
        if saved.is_none() || saved != expected {
            return Err(format!(
                "{who}: frame {frame} has checksum {saved:x?}, the plain run {expected:x?}"
            )
            .into());
        }
    }
    Ok(())
}

/// GGRS's `SyncTestSession`: roll back `check_distance` frames every frame and compare.
fn sync_test(frames: u32, reference: &[u64]) -> Result<(), Box<dyn Error>> {
    let mut session = SessionBuilder::<GgrsConfig>::new()
        .with_num_players(2)?
        .with_check_distance(7)
        .with_max_prediction_window(8)
        .start_synctest_session()?;
    let mut game = Game::new()?;
    for frame in 0..frames {
        for player in 0..2 {
            session.add_local_input(player, scripted_input(player, frame))?;
        }
        match session.advance_frame() {
            Ok(requests) => game.handle(requests)?,
            Err(GgrsError::MismatchedChecksum {
                current_frame,
                mismatched_frames,
            }) => {
                return Err(format!(
                    "sync test: resimulated checksums differ at frame {current_frame}: \
                     {mismatched_frames:?}"
                )
                .into())
            }
            Err(e) => return Err(e.into()),
        }
    }
    // The last frame saved is `frames - 1`.
    check("sync test", &game, reference, frames as Frame - 1)?;
    println!(
        "sync test: {frames} frames, {} rollbacks of 7 frames resimulated; every checksum \
         agreed, and every frame equals the plain run",
        game.loads,
    );
    Ok(())
}

/// A packet on the in-memory network.
struct Packet {
    deliver_at: u64,
    from: u8,
    to: u8,
    message: Message,
}

/// The in-memory network both peers share: a lossy, delaying, reordering wire.
struct Network {
    tick: u64,
    rng: SplitMix64,
    in_flight: VecDeque<Packet>,
    sent: u32,
    lost: u32,
}

impl Network {
    /// 10 % of the packets are lost; the rest arrive 1 to 5 ticks later.
    fn send(&mut self, from: u8, to: u8, message: &Message) {
        self.sent += 1;
        if self.rng.next_f32() < 0.10 {
            self.lost += 1;
            return;
        }
        let delay = 1 + self.rng.next_u64() % 5;
        self.in_flight.push_back(Packet {
            deliver_at: self.tick + delay,
            from,
            to,
            message: message.clone(),
        });
    }

    /// Everything due for `to` by now, in the order it is due (reordered by the delays).
    fn receive(&mut self, to: u8) -> Vec<(u8, Message)> {
        let mut due: Vec<Packet> = Vec::new();
        let mut kept = VecDeque::new();
        for p in self.in_flight.drain(..) {
            if p.to == to && p.deliver_at <= self.tick {
                due.push(p);
            } else {
                kept.push_back(p);
            }
        }
        self.in_flight = kept;
        due.sort_by_key(|p| p.deliver_at); // stable: same tick keeps sending order
        due.into_iter().map(|p| (p.from, p.message)).collect()
    }
}

/// One peer's end of the in-memory network: GGRS's `NonBlockingSocket`.
struct MemorySocket {
    me: u8,
    network: Rc<RefCell<Network>>,
}

impl NonBlockingSocket<u8> for MemorySocket {
    fn send_to(&mut self, msg: &Message, addr: &u8) {
        self.network.borrow_mut().send(self.me, *addr, msg);
    }

    fn receive_all_messages(&mut self) -> Vec<(u8, Message)> {
        self.network.borrow_mut().receive(self.me)
    }
}

/// Two `P2PSession` peers in one process over the lossy network; desync detection on.
fn peer_to_peer(frames: u32, reference: &[u64], desync: bool) -> Result<(), Box<dyn Error>> {
    let network = Rc::new(RefCell::new(Network {
        tick: 0,
        rng: SplitMix64::new(42),
        in_flight: VecDeque::new(),
        sent: 0,
        lost: 0,
    }));
    // Peer `me` plays player `me`; the other peer is remote.
    let start = |me: u8| -> Result<P2PSession<GgrsConfig>, GgrsError> {
        let other = 1 - me;
        SessionBuilder::<GgrsConfig>::new()
            .with_num_players(2)?
            .with_max_prediction_window(8)
            .with_desync_detection_mode(DesyncDetection::On { interval: 10 })
            .add_player(PlayerType::Local, usize::from(me))?
            .add_player(PlayerType::Remote(other), usize::from(other))?
            .start_p2p_session(MemorySocket {
                me,
                network: Rc::clone(&network),
            })
    };
    let t0 = std::time::Instant::now();
    let mut running_at = None;
    let mut sessions = [start(0)?, start(1)?];
    let mut games = [Game::new()?, Game::new()?];
    if desync {
        games[1].sabotage_at = Some(100);
    }
    // The last frame each peer had confirmed right after an advance: by then GGRS has
    // rolled back for every input it knew, so the saved states up to it are final.
    let mut confirmed: [Frame; 2] = [-1, -1];
    let mut desyncs = 0;

    // Each loop iteration is one network tick, and each peer tries to advance one frame.
    let mut ticks: u64 = 0;
    while confirmed.iter().any(|&c| c < frames as Frame) {
        ticks += 1;
        if ticks > 100_000 {
            return Err("peer to peer: no progress".into());
        }
        network.borrow_mut().tick += 1;
        for me in 0..2 {
            let (session, game) = (&mut sessions[me], &mut games[me]);
            session.poll_remote_clients();
            for event in session.events() {
                if let GgrsEvent::DesyncDetected {
                    frame,
                    local_checksum,
                    remote_checksum,
                    ..
                } = event
                {
                    desyncs += 1;
                    if desyncs > 2 {
                        continue; // the first one of each peer says enough
                    }
                    eprintln!(
                        "peer {me}: GGRS detected a desync at frame {frame}: \
                         {local_checksum:#x} vs {remote_checksum:#x}"
                    );
                }
            }
            if running_at.is_none() && session.current_state() == SessionState::Running {
                running_at = Some(t0.elapsed());
            }
            if session.current_state() != SessionState::Running {
                // The handshake retries every 200 ms of wall-clock time: let time pass.
                std::thread::sleep(std::time::Duration::from_micros(500));
                continue;
            }
            let frame = u32::try_from(session.current_frame()).unwrap_or(0);
            session.add_local_input(me, scripted_input(me, frame))?;
            match session.advance_frame() {
                // No `AdvanceFrame` among the requests when this peer is as far ahead of
                // the other's inputs as the prediction window allows: it waits.
                Ok(requests) => {
                    game.handle(requests)?;
                    confirmed[me] = session.confirmed_frame();
                }
                Err(GgrsError::PredictionThreshold) => {}
                Err(e) => return Err(e.into()),
            }
        }
    }

    if desyncs > 0 {
        return Err(format!("GGRS detected {desyncs} desyncs").into());
    }
    for (me, game) in games.iter().enumerate() {
        check(&format!("peer {me}"), game, reference, frames as Frame)?;
    }
    let net = network.borrow();
    println!(
        "peer to peer: {ticks} ticks ({:.0} ms, {:.0} of them in GGRS's handshake), {} \
         packets sent, {} lost; the peers rolled back {} and {} times; frames 0 to {frames} \
         of both equal the plain run; no desync reported",
        t0.elapsed().as_secs_f64() * 1e3,
        running_at.unwrap_or_default().as_secs_f64() * 1e3,
        net.sent,
        net.lost,
        games[0].loads,
        games[1].loads,
    );
    Ok(())
}

/// Both runs; an `Err` when any checksum disagrees. With `desync`, peer 1 nudges a ball
/// at frame 100 and the run must fail.
pub fn run(desync: bool) -> Result<(), Box<dyn Error>> {
    let frames = 300;
    let reference = reference(frames + 16)?;
    println!(
        "plain run: checksum at frame {frames}: {:#018x}",
        reference[frames as usize]
    );
    sync_test(frames, &reference)?;
    peer_to_peer(frames, &reference, desync)?;
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    run(std::env::args().any(|a| a == "--desync"))
}
