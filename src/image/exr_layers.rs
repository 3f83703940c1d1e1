//! Layered OpenEXR: several channel groups of one size (beauty, albedo,
//! normal, ...) in one file, with text metadata such as sample counts and
//! seeds.
//!
//! The file is a single part in the OpenEXR layer convention that every
//! viewer understands: a layer's channels are named "{layer}.{channel}"
//! ("albedo.R"), except for the layer with the empty name, whose channels are
//! stored bare ("R", "G", "B"). Viewers show those as the default image, so
//! the beauty belongs there, and [`super::read_image`] reads it back as RGB.
//! Samples are 32-bit floats with ZIP compression, so values read back
//! bit-exact. Metadata is stored as string attributes of the header.

use std::collections::BTreeMap;
use std::path::Path;

use ::exr::prelude::{
    read, AnyChannel, AnyChannels, AttributeValue, Encoding, FlatImage, FlatSamples, Image, Layer, LayerAttributes,
    ReadChannels as _, ReadLayers as _, Text, Vec2, WritableImage,
};

use super::atomic::write_atomically;
use super::exr::{check_header_sizes, exr_error};
use super::exr_header_order::sort_header_attributes;
use super::{check_size, file_name, ImageError, RgbImage};
use crate::input_file::{InputFiles, InputKind};

/// One group of channels, e.g. beauty "R", "G", "B", or depth "Z".
#[derive(Clone, Debug, PartialEq)]
pub struct ExrLayer {
    /// Prefix of the channel names in the file; empty for the top-level layer.
    pub name: String,
    /// Channel names without the layer prefix, e.g. ["R", "G", "B"], ["Y"]
    /// or ["X", "Y", "Z"]. Non-empty, without '.'.
    pub channels: Vec<String>,
    /// Interleaved per pixel (all channels of a pixel together), row-major,
    /// top row first: width * height * channels.len() values.
    pub data: Vec<f32>,
}

impl ExrLayer {
    /// An "R", "G", "B" layer holding `img`.
    pub fn rgb(name: impl Into<String>, img: &RgbImage) -> Self {
        Self {
            name: name.into(),
            channels: ["R", "G", "B"].map(String::from).to_vec(),
            data: img.pixels.iter().flatten().copied().collect(),
        }
    }
}

/// A layered EXR file. Order on reading: the top-level layer first, then the
/// others by name; within a layer R, G, B, A first, then the others by name.
/// (EXR stores channels sorted by name, so the order they were written in is
/// not kept.)
#[derive(Clone, Debug, PartialEq)]
pub struct ExrDocument {
    pub width: u32,
    pub height: u32,
    pub layers: Vec<ExrLayer>,
    /// Text metadata, e.g. "caustica.samples" -> "1024". Other attribute
    /// types in files from elsewhere are not read.
    pub attributes: BTreeMap<String, String>,
}

impl ExrDocument {
    /// The layer called `name` ("" for the top-level one), if present.
    pub fn layer(&self, name: &str) -> Option<&ExrLayer> {
        self.layers.iter().find(|layer| layer.name == name)
    }
}

/// Writes `doc` atomically. Fails without touching the file system if the
/// document is inconsistent (data length, empty or duplicate channel names).
pub fn write_exr_document(path: &Path, doc: &ExrDocument) -> Result<(), ImageError> {
    check_size(&file_name(path), doc.width.into(), doc.height.into())?;
    let layer = encode(doc).map_err(|reason| ImageError::ExrLayout { file: file_name(path), reason })?;
    let image = Image::from_layer(layer);
    // Encoded in memory first, so the header's attributes can be put in one order (equal images,
    // equal files: see exr_header_order).
    let mut encoded = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut encoded).map_err(|e| exr_error(path, e))?;
    let mut bytes = encoded.into_inner();
    sort_header_attributes(&mut bytes);
    write_atomically(path, |out| {
        std::io::Write::write_all(out, &bytes).map_err(|cause| ImageError::Io { file: file_name(path), cause })
    })
}

/// Reads every channel of every layer (half and u32 samples converted to
/// f32) and the text attributes. Files with several parts are accepted if
/// all parts have the same size; a part's name then prefixes its channels.
/// Partial renders come from the command line (`merge`, `--resume`), so from anywhere; they are
/// read as the crate's `read_all_flat_layers_from_file` would, through [`InputFiles`].
pub fn read_exr_document(path: &Path) -> Result<ExrDocument, ImageError> {
    let (files, kind) = (InputFiles::anywhere(), InputKind::PartialRender);
    check_header_sizes(&files, path, kind)?;
    let file = std::io::BufReader::new(files.open(path, kind)?);
    let image: FlatImage = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(file)
        .map_err(|e| exr_error(path, e))?;
    decode(&image).map_err(|reason| ImageError::ExrLayout { file: file_name(path), reason })
}

fn encode(doc: &ExrDocument) -> Result<Layer<AnyChannels<FlatSamples>>, String> {
    let (width, height) = (doc.width as usize, doc.height as usize);
    if width == 0 || height == 0 {
        return Err(format!("image of {width} x {height} pixels is empty"));
    }
    if doc.layers.is_empty() {
        return Err("no layers".to_owned());
    }
    let pixels = width * height;
    let mut channels = Vec::new();
    let mut full_names = std::collections::BTreeSet::new();
    for layer in &doc.layers {
        let count = layer.channels.len();
        if count == 0 {
            return Err(format!("layer '{}' has no channels", layer.name));
        }
        if layer.data.len() != pixels * count {
            return Err(format!(
                "layer '{}' has {} values, expected {width} x {height} pixels x {count} channels",
                layer.name,
                layer.data.len()
            ));
        }
        for (i, channel) in layer.channels.iter().enumerate() {
            // A '.' would move part of the channel name into the layer name
            // on reading.
            if channel.is_empty() || channel.contains('.') {
                return Err(format!(
                    "channel '{channel}' of layer '{}': channel names must be non-empty and contain no '.'",
                    layer.name
                ));
            }
            let full = if layer.name.is_empty() { channel.clone() } else { format!("{}.{channel}", layer.name) };
            let name = name_text(&full)?;
            if !full_names.insert(full) {
                return Err(format!("channel '{name}' appears twice"));
            }
            let samples = layer.data.iter().skip(i).step_by(count).copied().collect();
            channels.push(AnyChannel::new(name, FlatSamples::F32(samples)));
        }
    }

    let mut attributes = LayerAttributes::default();
    for (name, value) in &doc.attributes {
        // Attribute values are length-prefixed, so any bytes go; UTF-8 is
        // what OpenEXR's own tools assume for strings.
        let value = AttributeValue::Text(Text::from_slice_unchecked(value.as_bytes()));
        attributes.other.insert(name_text(name)?, value);
    }
    let encoding = Encoding::SMALL_LOSSLESS;
    Ok(Layer::new(Vec2(width, height), attributes, encoding, AnyChannels::sort(channels.into())))
}

/// Channel and attribute names are NUL-terminated in the file, and the
/// format limits them to 255 bytes.
fn name_text(name: &str) -> Result<Text, String> {
    if name.is_empty() || name.len() > 255 || name.contains('\0') {
        return Err(format!("name '{}' must be 1 to 255 bytes without NUL", name.escape_debug()));
    }
    Ok(Text::from_slice_unchecked(name.as_bytes()))
}

fn text_string(text: &Text) -> String {
    String::from_utf8_lossy(text.bytes()).into_owned()
}

fn decode(image: &FlatImage) -> Result<ExrDocument, String> {
    let first = image.layer_data.first().ok_or("no layers")?;
    let size = first.size;
    let pixels = size.area();
    // Layer name -> (channel name, samples), both sorted as documented.
    let mut grouped: BTreeMap<String, Vec<(String, Vec<f32>)>> = BTreeMap::new();
    let mut attributes = BTreeMap::new();
    for part in &image.layer_data {
        if part.size != size {
            return Err(format!(
                "parts of different sizes: {} x {} and {} x {}",
                size.0, size.1, part.size.0, part.size.1
            ));
        }
        for (name, value) in &part.attributes.other {
            if let AttributeValue::Text(value) = value {
                attributes.entry(text_string(name)).or_insert_with(|| text_string(value));
            }
        }
        let prefix = part.attributes.layer_name.as_ref().map(text_string);
        for channel in &part.channel_data.list {
            let full = match &prefix {
                Some(prefix) => format!("{prefix}.{}", text_string(&channel.name)),
                None => text_string(&channel.name),
            };
            let samples: Vec<f32> = match &channel.sample_data {
                FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
                FlatSamples::F32(v) => v.clone(),
                FlatSamples::U32(v) => v.iter().map(|&u| u as f32).collect(),
            };
            // Subsampled channels have fewer samples; they would need
            // upsampling, which nothing here wants.
            if samples.len() != pixels {
                return Err(format!("channel '{full}' has {} samples for {pixels} pixels", samples.len()));
            }
            let (layer, name) = match full.rsplit_once('.') {
                Some((layer, name)) => (layer.to_owned(), name.to_owned()),
                None => (String::new(), full),
            };
            grouped.entry(layer).or_default().push((name, samples));
        }
    }

    let layers = grouped
        .into_iter()
        .map(|(name, mut channels)| {
            channels.sort_by(|(a, _), (b, _)| (rgba_rank(a), a).cmp(&(rgba_rank(b), b)));
            let mut data = Vec::with_capacity(pixels * channels.len());
            for i in 0..pixels {
                data.extend(channels.iter().map(|(_, samples)| samples[i]));
            }
            ExrLayer { name, channels: channels.into_iter().map(|(name, _)| name).collect(), data }
        })
        .collect();
    Ok(ExrDocument {
        // The caller checked sizes against MAX_PIXELS (2^28), so they fit.
        width: size.0 as u32,
        height: size.1 as u32,
        layers,
        attributes,
    })
}

/// R, G, B, A in that order, before any other channel.
fn rgba_rank(channel: &str) -> usize {
    ["R", "G", "B", "A"].iter().position(|&c| c == channel).unwrap_or(4)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::{file_names, temp_dir};

    fn strings(names: &[&str]) -> Vec<String> {
        names.iter().map(|&n| n.to_owned()).collect()
    }

    /// 3 x 2 pixels; every value distinct so that any transposition, row
    /// flip or channel swap shows. Listed in the order reading returns.
    fn document() -> ExrDocument {
        let (width, height) = (3u32, 2u32);
        let layer = |name: &str, channels: &[&str], base: f32| {
            let count = (width * height) as usize * channels.len();
            ExrLayer {
                name: name.to_owned(),
                channels: strings(channels),
                data: (0..count).map(|i| base + i as f32 * 0.001_001).collect(),
            }
        };
        let mut beauty = layer("", &["R", "G", "B"], 1.0);
        // Values that f16 or a lossy codec would not keep.
        beauty.data[..6].copy_from_slice(&[
            f32::MIN_POSITIVE,
            f32::from_bits(1), // smallest subnormal
            f32::MAX,
            -0.0,
            1e30,
            -1e-30,
        ]);
        beauty.data[6] = f32::from_bits(0x7fc0_1234); // NaN with a payload
        let attributes = [
            ("caustica.samples", "1024"),
            ("caustica.seed", "7"),
            ("caustica.scene_hash", "9f86d081884c7d65"),
            ("caustica.sample_offset", "0"),
            ("caustica.note", "Grüße, \u{1F4F7}"),
        ];
        ExrDocument {
            width,
            height,
            layers: vec![
                beauty,
                layer("albedo", &["R", "G", "B"], 2.0),
                layer("normal", &["X", "Y", "Z"], -3.0),
                layer("variance", &["Y"], 4.0),
            ],
            attributes: attributes.iter().map(|&(k, v)| (k.to_owned(), v.to_owned())).collect(),
        }
    }

    /// Equality on bits, so that NaN and -0.0 count.
    fn assert_bit_exact(back: &ExrDocument, doc: &ExrDocument) {
        let bits = |d: &ExrDocument| -> Vec<(String, Vec<String>, Vec<u32>)> {
            d.layers
                .iter()
                .map(|l| {
                    let bits = l.data.iter().map(|v| v.to_bits()).collect();
                    (l.name.clone(), l.channels.clone(), bits)
                })
                .collect()
        };
        assert_eq!((back.width, back.height), (doc.width, doc.height));
        assert_eq!(bits(back), bits(doc));
        assert_eq!(back.attributes, doc.attributes);
    }

    #[test]
    fn round_trip_is_bit_exact_with_attributes() {
        let dir = temp_dir("roundtrip");
        let path = dir.join("render.exr");
        let doc = document();
        write_exr_document(&path, &doc).unwrap();
        let back = read_exr_document(&path);
        let names = file_names(&dir);
        assert_bit_exact(&back.unwrap(), &doc);
        // Only the target: the temporary file was renamed over it.
        assert_eq!(names, ["render.exr"]);
    }

    #[test]
    fn read_image_reads_the_beauty() {
        let dir = temp_dir("beauty");
        let path = dir.join("render.exr");
        let mut beauty = RgbImage::new(2, 2);
        beauty.set(1, 0, [0.25, 0.5, 0.75]);
        beauty.set(0, 1, [8.0, 16.0, 32.0]);
        let mut albedo = RgbImage::new(2, 2);
        albedo.set(0, 0, [0.9, 0.8, 0.7]);
        let doc = ExrDocument {
            width: 2,
            height: 2,
            // Albedo first: the file, not the list, decides what is default.
            layers: vec![ExrLayer::rgb("albedo", &albedo), ExrLayer::rgb("", &beauty)],
            attributes: BTreeMap::new(),
        };
        write_exr_document(&path, &doc).unwrap();
        let read = crate::image::read_image(&path);
        let back = read_exr_document(&path);
        assert_eq!(read.unwrap(), beauty);
        let back = back.unwrap();
        assert_eq!(back.layer("albedo"), Some(&ExrLayer::rgb("albedo", &albedo)));
        assert_eq!(back.layers[0], ExrLayer::rgb("", &beauty));
    }

    #[test]
    fn channels_come_back_in_documented_order() {
        let dir = temp_dir("order");
        let path = dir.join("order.exr");
        let doc = ExrDocument {
            width: 1,
            height: 1,
            layers: vec![
                ExrLayer { name: "normal".to_owned(), channels: strings(&["Z", "Y", "X"]), data: vec![3.0, 2.0, 1.0] },
                ExrLayer {
                    name: String::new(),
                    channels: strings(&["A", "B", "G", "R"]),
                    data: vec![4.0, 3.0, 2.0, 1.0],
                },
            ],
            attributes: BTreeMap::new(),
        };
        write_exr_document(&path, &doc).unwrap();
        let back = read_exr_document(&path);
        let back = back.unwrap();
        assert_eq!(back.layers[0].channels, strings(&["R", "G", "B", "A"]));
        assert_eq!(back.layers[0].data, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(back.layers[1].channels, strings(&["X", "Y", "Z"]));
        assert_eq!(back.layers[1].data, [1.0, 2.0, 3.0]);
    }

    #[test]
    fn inconsistent_documents_are_rejected_leaving_no_file() {
        let dir = temp_dir("invalid");
        let path = dir.join("bad.exr");
        let reject = |edit: &dyn Fn(&mut ExrDocument)| {
            let mut doc = document();
            edit(&mut doc);
            let err = write_exr_document(&path, &doc).unwrap_err().to_string();
            assert!(err.starts_with(&format!("{}: ", path.display())), "{err}");
            err
        };
        let err = reject(&|d| {
            d.layers[1].data.pop();
        });
        assert!(err.contains("layer 'albedo' has 17 values"), "{err}");
        let err = reject(&|d| d.layers[2].channels[0] = "X.1".to_owned());
        assert!(err.contains("channel 'X.1' of layer 'normal'"), "{err}");
        let err = reject(&|d| d.layers[3].name = "normal".to_owned());
        assert!(err.contains("channel 'normal.Y' appears twice"), "{err}");
        let err = reject(&|d| d.layers.clear());
        assert!(err.contains("no layers"), "{err}");
        let err = reject(&|d| {
            d.attributes.insert(String::new(), "x".to_owned());
        });
        assert!(err.contains("name '' must be 1 to 255 bytes"), "{err}");
        // Standard attribute names are the crate's to write; it refuses them
        // only once writing has begun, so this also covers temp clean-up.
        let err = reject(&|d| {
            d.attributes.insert("owner".to_owned(), "me".to_owned());
        });
        assert!(err.contains("reserved"), "{err}");
        let err = reject(&|d| {
            d.width = 1 << 20;
            d.height = 1 << 20;
        });
        assert!(err.contains("too large"), "{err}");
        let names = file_names(&dir);
        assert!(names.is_empty(), "{names:?}");
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_path() {
        let path = Path::new("/nonexistent/caustica/render.exr");
        let err = write_exr_document(path, &document()).unwrap_err().to_string();
        assert!(err.starts_with("/nonexistent/caustica/render.exr: "), "{err}");
    }

    #[test]
    fn truncated_or_corrupt_files_are_errors_naming_the_file() {
        let dir = temp_dir("corrupt");
        let good = dir.join("good.exr");
        write_exr_document(&good, &document()).unwrap();
        let bytes = std::fs::read(&good).unwrap();
        let path = dir.join("bad.exr");
        let mut failures = Vec::new();
        // Every proper prefix must fail; flipped bytes may happen to decode
        // (e.g. in a pixel value) but must never panic.
        for len in 0..bytes.len() {
            std::fs::write(&path, &bytes[..len]).unwrap();
            match read_exr_document(&path) {
                Ok(_) => failures.push(format!("prefix of {len} bytes was accepted")),
                Err(e) if !e.to_string().starts_with(&format!("{}: ", path.display())) => failures.push(format!("{e}")),
                Err(_) => {}
            }
        }
        for i in 0..bytes.len() {
            let mut corrupt = bytes.clone();
            corrupt[i] ^= 0xff;
            std::fs::write(&path, &corrupt).unwrap();
            if let Err(e) = read_exr_document(&path) {
                if !e.to_string().starts_with(&format!("{}: ", path.display())) {
                    failures.push(format!("{e}"));
                }
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
    }

    #[test]
    fn huge_header_is_rejected_before_allocating() {
        let dir = temp_dir("huge");
        let path = dir.join("huge.exr");
        write_exr_document(&path, &document()).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        // dataWindow is a box2i: name, type, size 16, then xMin yMin xMax yMax.
        let key = b"dataWindow\0box2i\0";
        let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
        for (offset, value) in [(8, 999_999i32), (12, 999_999)] {
            bytes[at + offset..at + offset + 4].copy_from_slice(&value.to_le_bytes());
        }
        std::fs::write(&path, &bytes).unwrap();
        let err = read_exr_document(&path).unwrap_err().to_string();
        let plain = crate::image::read_image(&path).unwrap_err().to_string();
        let expected =
            format!("{}: image of 1000000 x 1000000 pixels is too large (limit 2^28 pixels)", path.display());
        assert_eq!(err, expected);
        assert_eq!(plain, expected);
    }
}
