//! When a batch's rays travel as packets. Packets return
//! exactly the hits of single rays, so this decides speed, never the image.

use crate::accel::PACKET_SIZE;

crate::mode::mode_enum! {
    /// Whether a batch's camera rays and shadow rays are traced as packets.
    #[derive(Default)]
    pub enum PacketMode("packet mode") {
        /// Packets where they were measured to pay: a batch's camera rays
        /// when there are at least [`CAMERA_PACKET_MIN`], its shadow rays
        /// towards one light sample when at least [`SHADOW_PACKET_MIN`]
        /// (never). Single rays otherwise.
        #[default]
        Auto = "auto",
        /// A batch's rays as a packet, however few they are.
        On = "on",
        /// Single rays only.
        Off = "off",
    }
}

// The `auto` thresholds, from the packet/single throughput of the renderer's
// own batches (docs/performance.md, "Packets"; reproduce with `cargo test
// --release --test render_packets -- --ignored --nocapture`), medians of 15
// alternating runs on a shared 2-core machine. Re-measured after packets
// began testing each leaf triangle against all their rays at once:
// - camera batches (one pixel's pixel and lens samples): at 8 rays 1.15x
//   (bunny, thin lens), 1.44x (bunny, pinhole), 1.13x (scenes/thin-lens.toml,
//   one node) and 1.66x (scenes/mesh.toml); at 7 rays 1.00-1.37x; at 6 rays
//   1.00-1.25x; below 6 rays 0.3-1.0x. Scene size no longer matters;
// - shadow batches (then 8 stratified samples from one hit towards a rect
//   light): 0.83-1.05x at every size, never a clear gain; about half of
//   them differed in direction sign (the light straddles the point) and
//   then fell back to single rays inside `Scene::occluded_packet`.
// (Before that change packets lost below 8 camera rays everywhere and won
// only on 1000+ node scenes at 8, so `auto` needed a node threshold.)
// Re-measured after packets began travelling with mixed signs and
// measuring slabs from an apex: camera batches at 8 rays 1.14-2.50x, at 7
// rays 1.00-1.67x, at 6 rays 1.00-1.67x; shadow batches 0.76-0.87x at 3
// to 8 rays (one origin, but eight points on the light spread too wide).
// Re-measured when shadow rays began travelling in waves (one from each
// hit of a pixel's batch, towards one light; `shade::direct`): waves of 8
// rays 0.87x (bunny, thin lens) and 0.93x (bunny, pinhole). Whole renders
// with waves of at least 4 or 6 rays as packets, against none, in one
// process, alternating, nine runs, one thread: within 2% either way on
// seed-mc, soft-shadow, the bunny and both dragon scenes.
// The thresholds stand.

/// Fewest camera rays a batch must have for `auto` to trace them as a packet.
pub const CAMERA_PACKET_MIN: usize = 7;
/// Fewest shadow rays towards one light sample a batch must have for `auto`
/// to trace them as a packet: more than a packet holds, so never (see above).
pub const SHADOW_PACKET_MIN: usize = PACKET_SIZE + 1;

impl PacketMode {
    /// Trace `live` rays of a batch as a packet, where `auto` asks for at
    /// least `auto_min`?
    #[inline]
    pub fn use_packet(self, live: usize, auto_min: usize) -> bool {
        match self {
            Self::Auto => live >= auto_min,
            Self::On => live > 0,
            Self::Off => false,
        }
    }
}
