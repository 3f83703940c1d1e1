//! The overlay: what the viewer is doing (samples, speed, frame time, device, settings) and the
//! keys, drawn with egui over the picture, at the top left and no wider than [`WIDTH`] points. It
//! collapses (or its key list does) with a click on its title.

/// The keys, as the overlay and docs/cli.md list them.
pub const KEYS: [(&str, &str); 14] = [
    ("left drag", "orbit around the pivot"),
    ("middle drag", "pan (or shift + left drag)"),
    ("wheel", "dolly to / from the pivot"),
    ("right drag", "look around (fly)"),
    ("right + WASD QE", "fly (shift: faster)"),
    ("F", "frame the whole scene"),
    ("+ / -", "exposure, half a stop"),
    ("T", "next tonemapper"),
    ("1 2 3 4", "beauty, albedo, normal, depth"),
    ("P", "print the camera as TOML"),
    ("S", "save PNG and EXR"),
    ("R", "reload (also on file change)"),
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

/// Widest the overlay gets, in points: the picture stays visible beside it.
pub const WIDTH: f32 = 250.0;

pub fn draw(ctx: &egui::Context, status: &Status) {
    egui::Window::new("caustica").default_pos([8.0, 8.0]).max_width(WIDTH).resizable(false).show(ctx, |ui| {
        ui.style_mut().override_text_style = Some(egui::TextStyle::Small);
        egui::Grid::new("status").num_columns(2).show(ui, |ui| {
            let mut row = |name: &str, value: String| {
                ui.label(name);
                ui.label(value);
                ui.end_row();
            };
            row("scene", status.scene.to_owned());
            row("device", status.device.to_owned());
            row("image", format!("{} x {}", status.size[0], status.size[1]));
            row(
                "samples",
                match status.limit {
                    Some(limit) => format!("{} / {limit} spp", status.samples),
                    None => format!("{} spp", status.samples),
                },
            );
            row("speed", format!("{:.2} Msamples/s", status.samples_per_second / 1e6));
            row(
                "frame",
                format!("{:.1} ms ({:.0} fps)", status.frame_seconds * 1e3, 1.0 / status.frame_seconds.max(1e-6)),
            );
            row("exposure", format!("{:+.1} EV", status.exposure));
            row("tonemap", status.tonemap.to_owned());
            row("view", status.view.to_owned());
            row("seed", status.seed.to_string());
        });
        if let Some(problem) = status.problem {
            ui.colored_label(egui::Color32::from_rgb(255, 120, 100), problem);
        }
        egui::CollapsingHeader::new("keys").default_open(true).show(ui, |ui| {
            egui::Grid::new("keys").num_columns(2).show(ui, |ui| {
                for (key, what) in KEYS {
                    ui.strong(key);
                    ui.label(what);
                    ui.end_row();
                }
            });
        });
    });
}
