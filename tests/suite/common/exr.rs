//! Reading back the EXR files the binary writes, channels by name.

use exr::prelude::{read, ReadChannels, ReadLayers};
use std::path::Path;

/// An EXR's data window origin and size, its display size, its channels by
/// name (row-major values) and its header attributes.
pub struct Exr {
    pub origin: (i32, i32),
    pub size: (usize, usize),
    pub display: (usize, usize),
    pub channels: Vec<(String, Vec<f32>)>,
    pub layer: exr::meta::header::LayerAttributes,
}

pub fn read_exr(path: &Path) -> Exr {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let layer = image.layer_data;
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    Exr {
        origin: (
            layer.attributes.layer_position.0,
            layer.attributes.layer_position.1,
        ),
        size: (layer.size.0, layer.size.1),
        display: (
            image.attributes.display_window.size.0,
            image.attributes.display_window.size.1,
        ),
        channels,
        layer: layer.attributes,
    }
}

impl Exr {
    /// The values of the channel called `name`, which must exist.
    pub fn channel(&self, name: &str) -> &[f32] {
        let found = self.channels.iter().find(|(n, _)| n == name);
        &found.unwrap_or_else(|| panic!("no channel {name}")).1
    }
}
