#![no_main]
//! PFM decoder: any bytes must give an image or an error, never a panic or a huge allocation.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(img) = caustica::image::pfm::decode(data, "fuzz.pfm") {
        assert_eq!(img.pixels.len(), img.width as usize * img.height as usize);
        let _ = caustica::image::pfm::check_finite(&img, "fuzz.pfm");
    }
});
