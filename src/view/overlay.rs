//! The overlay: what the viewer is doing (samples, speed, frame time, device, settings) and the
//! keys, drawn with egui over the picture. It can be collapsed by clicking its title.

/// The keys, as the overlay and the README list them.
pub const KEYS: [(&str, &str); 14] = [
    ("left drag", "orbit around the pivot"),
    ("middle drag, shift + left drag", "pan"),
    ("wheel", "dolly towards / away from the pivot"),
    ("right drag", "look around (fly)"),
    ("right drag + W A S D / Q E", "fly forward, left, back, right / down, up (shift: faster)"),
    ("F", "frame the whole scene"),
    ("+ / -", "exposure up / down half a stop"),
    ("T", "next tonemapper (clamp, reinhard, aces)"),
    ("1 2 3 4", "show beauty, albedo, normal, depth"),
    ("P", "print the camera as a TOML [camera] block"),
    ("S", "save the image: PNG, and EXR with the accumulation"),
    ("R", "reload the scene (also automatic when its files change)"),
    ("drop a file", "open it"),
    ("Esc", "quit"),
];

/// What the overlay shows.
pub struct Status<'a> {
    pub scene: &'a str,
    pub device: &'a str,
    pub size: [u32; 2],
    pub samples: u32,
    pub limit: Option<u32>,
    pub samples_per_second: f64,
    pub frame_seconds: f64,
    pub exposure: f32,
    pub tonemap: &'a str,
    pub view: &'a str,
    pub seed: u32,
    /// Why the last reload failed, or nothing.
    pub problem: Option<&'a str>,
}

pub fn draw(ctx: &egui::Context, status: &Status) {
    egui::Window::new("caustica").default_pos([8.0, 8.0]).resizable(false).default_open(true).show(ctx, |ui| {
        egui::Grid::new("status").num_columns(2).show(ui, |ui| {
            let mut row = |name: &str, value: String| {
                ui.label(name);
                ui.label(value);
                ui.end_row();
            };
            row("scene", status.scene.to_owned());
            row("device", status.device.to_owned());
            row("image", format!("{} x {}", status.size[0], status.size[1]));
            row("samples", match status.limit {
                Some(limit) => format!("{} / {limit} spp", status.samples),
                None => format!("{} spp", status.samples),
            });
            row("speed", format!("{:.2} Msamples/s", status.samples_per_second / 1e6));
            row("frame", format!("{:.1} ms ({:.0} fps)", status.frame_seconds * 1e3, 1.0 / status.frame_seconds.max(1e-6)));
            row("exposure", format!("{:+.1} EV", status.exposure));
            row("tonemap", status.tonemap.to_owned());
            row("view", status.view.to_owned());
            row("seed", status.seed.to_string());
        });
        if let Some(problem) = status.problem {
            ui.colored_label(egui::Color32::from_rgb(255, 120, 100), problem);
        }
        ui.separator();
        egui::Grid::new("keys").num_columns(2).show(ui, |ui| {
            for (key, what) in KEYS {
                ui.strong(key);
                ui.label(what);
                ui.end_row();
            }
        });
    });
}
