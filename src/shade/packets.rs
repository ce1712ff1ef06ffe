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

// The `auto` thresholds, from the packet/single throughput of the
// renderer's own batches: a batch's camera rays pay as a packet from 7
// rays, its shadow rays towards one light sample never clearly did
// (docs/performance.md, "Measurements behind the renderer's defaults").

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
