//! How the kernel runs on a device: the one place that decides the run-time choices of a kernel
//! variant (variant.rs) that are not the scene's. Each choice gives the same image bit for bit
//! (each has a test that says so); only the speed differs, and it differs by device, so each
//! device class has its defaults, in [`Defaults::for_class`], with the measurement that chose
//! each entry.
//!
//! A user or a script overrides a default for an A/B of one binary with `--kernel-option
//! KEY=VALUE` on `render` and `bench` ([`KernelOptions::set_assignment`]), or with the matching
//! `CAUSTICA_*` environment variable ([`KernelOptions::from_env`]; the command line wins). The
//! keys ([`OPTIONS`]): `wavefront`, `walk-queue`, `walk-records`, `take-tiles`, `workgroup`,
//! `bvh-width`, `shadow-walk`.
//! Values that run nowhere by default are labelled experimental in [`OPTIONS`]: they are built
//! and tested, but no device class has measured a gain from them.

use super::bvh_width::BvhWidth;
use super::features::SceneFeatures;
use super::layout::GpuInstance;
use super::shadow_walk::ShadowWalk;
use super::tile_taking;
use super::walk_queue::{QueueRequest, WalkQueue};
use super::walk_records::WalkRecords;
use super::workgroup::Workgroup;
use crate::bvh::WideNode;
use crate::gpu::DeviceInfo;
use anyhow::{anyhow, bail, Result};

pub const WAVEFRONT_VAR: &str = "CAUSTICA_WAVEFRONT";
pub const WALK_QUEUE_VAR: &str = "CAUSTICA_WALK_QUEUE";
pub const WALK_RECORDS_VAR: &str = "CAUSTICA_WALK_RECORDS";
pub const TAKE_TILES_VAR: &str = "CAUSTICA_TAKE_TILES";
pub const WORKGROUP_VAR: &str = "CAUSTICA_WORKGROUP";
pub const BVH_WIDTH_VAR: &str = "CAUSTICA_BVH_WIDTH";
pub const SHADOW_WALK_VAR: &str = "CAUSTICA_SHADOW_WALK";

/// One run-time choice of the kernel: its key on the command line, its environment variable,
/// the values it takes and which of them are experimental.
pub struct KernelOption {
    pub key: &'static str,
    pub variable: &'static str,
    /// The values, each with what it does.
    pub values: &'static str,
    /// The values that no device class runs by default, and why they are kept.
    pub experimental: &'static str,
}

/// Every kernel option, in the order `--kernel-option help` lists them.
pub const OPTIONS: [KernelOption; 7] = [
    KernelOption {
        key: "wavefront",
        variable: WAVEFRONT_VAR,
        values: "1: the path loop split into three kernels a round (wavefront.rs); 0: the megakernel",
        experimental: "1 everywhere: on lavapipe it is 2-5x slower; on a GPU it is built for an A/B not yet measured",
    },
    KernelOption {
        key: "walk-queue",
        variable: WALK_QUEUE_VAR,
        values: "0: no queue; 1: rays walked from a queue the subgroup shares (walk_queue.rs), on any device; \
                 barriers: also with subgroup barriers on lavapipe",
        experimental: "1 on a GPU (with subgroup barriers) and barriers on lavapipe: unmeasured, and slower there",
    },
    KernelOption {
        key: "walk-records",
        variable: WALK_RECORDS_VAR,
        values: "texels: BVH nodes and triangles read from uniform texel buffers; storage: from storage buffers",
        experimental: "none: each value is some device's default",
    },
    KernelOption {
        key: "take-tiles",
        variable: TAKE_TILES_VAR,
        values: "1: subgroups take their tiles from a counter (tile_taking.rs); 0: each workgroup its own pixels",
        experimental: "1 on a GPU: a GPU hands out workgroups as its units free up; unmeasured",
    },
    KernelOption {
        key: "workgroup",
        variable: WORKGROUP_VAR,
        values: "WxH: the kernel's workgroup shape, powers of two, at most 128 invocations (workgroup.rs)",
        experimental: "every shape but 8x8: no device measured gains more than 3 % from another",
    },
    KernelOption {
        key: "bvh-width",
        variable: BVH_WIDTH_VAR,
        values: "4: four-wide nodes sorted at each visit; 8: eight-wide compressed nodes in the ray's octant order \
                 (bvh_width.rs), without the walk queue",
        experimental: "8 everywhere: built for GPUs without ray-tracing hardware, unmeasured there; slower on lavapipe",
    },
    KernelOption {
        key: "shadow-walk",
        variable: SHADOW_WALK_VAR,
        values: "sorted: a shadow ray's four-wide walk sorts each node's children as the closest hit's does; \
                 unsorted: it takes them in stored order (shadow_walk.rs)",
        experimental: "unsorted everywhere: unmeasured on a GPU",
    },
];

/// What was asked of the kernel, option by option; `None` leaves the choice to the device
/// class's [`Defaults`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KernelOptions {
    pub wavefront: Option<bool>,
    pub walk_queue: Option<QueueRequest>,
    pub walk_records: Option<WalkRecords>,
    pub take_tiles: Option<bool>,
    pub workgroup: Option<Workgroup>,
    pub bvh_width: Option<BvhWidth>,
    pub shadow_walk: Option<ShadowWalk>,
}

impl KernelOptions {
    /// The options the `CAUSTICA_*` environment variables set; an error names the variable.
    pub fn from_env() -> Result<KernelOptions> {
        let mut options = KernelOptions::default();
        for option in &OPTIONS {
            if let Ok(value) = std::env::var(option.variable) {
                options.set(option.key, &value).map_err(|e| anyhow!("{}={value}: {e}", option.variable))?;
            }
        }
        Ok(options)
    }

    /// The environment's options overridden by `assignments` (`KEY=VALUE` each, the command
    /// line's `--kernel-option`).
    pub fn from_env_and(assignments: &[String]) -> Result<KernelOptions> {
        let mut options = KernelOptions::from_env()?;
        for assignment in assignments {
            options.set_assignment(assignment)?;
        }
        Ok(options)
    }

    /// Sets the option that `KEY=VALUE` names; an error quotes the assignment.
    pub fn set_assignment(&mut self, assignment: &str) -> Result<()> {
        let Some((key, value)) = assignment.split_once('=') else {
            bail!("--kernel-option {assignment}: expected KEY=VALUE; {}", keys_hint());
        };
        self.set(key.trim(), value.trim()).map_err(|e| anyhow!("--kernel-option {assignment}: {e}"))
    }

    /// Sets option `key` to `value`.
    pub fn set(&mut self, key: &str, value: &str) -> Result<()> {
        match key {
            "wavefront" => self.wavefront = Some(zero_or_one(value, "the megakernel", "the wavefront")?),
            "walk-queue" => {
                self.walk_queue = Some(match value {
                    "0" => QueueRequest::Off,
                    "1" => QueueRequest::On,
                    "barriers" => QueueRequest::WithBarriers,
                    _ => bail!(
                        "expected 0 (no queue), 1 (the queue on any device) or barriers (with subgroup barriers on lavapipe too)"
                    ),
                })
            }
            "walk-records" => {
                self.walk_records = Some(match value {
                    "texels" => WalkRecords::Texels,
                    "storage" => WalkRecords::Storage,
                    _ => bail!("expected texels (uniform texel buffers) or storage (storage buffers)"),
                })
            }
            "take-tiles" => {
                self.take_tiles = Some(zero_or_one(
                    value,
                    "each workgroup renders its own pixels",
                    "subgroups take tiles from a counter",
                )?)
            }
            "workgroup" => self.workgroup = Some(Workgroup::parse(value)?),
            "bvh-width" => {
                self.bvh_width = Some(match value {
                    "4" => BvhWidth::Four,
                    "8" => BvhWidth::Eight,
                    _ => bail!("expected 4 (four-wide nodes) or 8 (eight-wide compressed nodes)"),
                })
            }
            "shadow-walk" => {
                self.shadow_walk = Some(match value {
                    "sorted" => ShadowWalk::Sorted,
                    "unsorted" => ShadowWalk::Unsorted,
                    _ => bail!("expected sorted (children nearest first) or unsorted (in stored order)"),
                })
            }
            _ => bail!("no kernel option '{key}'; {}", keys_hint()),
        }
        Ok(())
    }
}

fn zero_or_one(value: &str, zero: &str, one: &str) -> Result<bool> {
    match value {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => bail!("expected 0 ({zero}) or 1 ({one})"),
    }
}

fn keys_hint() -> String {
    let keys: Vec<&str> = OPTIONS.iter().map(|o| o.key).collect();
    format!("the keys are {} (--kernel-option help lists their values)", keys.join(", "))
}

/// `--kernel-option help`: every option, its values, which are experimental, and each device
/// class's default.
pub fn help() -> String {
    let mut out = String::from("Kernel options (--kernel-option KEY=VALUE, or the environment variable):\n");
    for option in &OPTIONS {
        out += &format!(
            "  {} ({}): {}\n    experimental: {}\n",
            option.key, option.variable, option.values, option.experimental
        );
    }
    out += "Defaults by device class:\n";
    for class in DeviceClass::ALL {
        let d = Defaults::for_class(class);
        out += &format!(
            "  {}: wavefront {}, walk-queue {}, walk-records {}, take-tiles {}, workgroup {}, bvh-width {}, shadow-walk {}\n",
            class.label(),
            u32::from(d.wavefront),
            if d.walk_queue { "1 (where the scene qualifies)" } else { "0" },
            d.walk_records.label(),
            if d.take_tiles { "1 (where possible)" } else { "0" },
            d.workgroup.label(),
            d.bvh_width.label(),
            d.shadow_walk.label()
        );
    }
    out
}

/// The kinds of device whose defaults differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceClass {
    /// Any GPU (the defaults were measured on an NVIDIA H200).
    Gpu,
    /// Mesa's lavapipe on an AMD CPU with Mesa 25: where storage buffers beat texel buffers.
    LavapipeMesa25Amd,
    /// Mesa's lavapipe whose loops run to their end (Mesa 24 and later), any other CPU or Mesa.
    Lavapipe,
    /// Mesa's lavapipe before Mesa 24, which silently ends shader loops after 65,535 iterations
    /// (loop_limit.glsl).
    LavapipeWithLoopLimit,
    /// A CPU device other than lavapipe (unmeasured): it splits a dispatch among its threads up
    /// front like lavapipe, but its lanes need not run in step as the walk queue's do there.
    OtherCpu,
}

impl DeviceClass {
    pub const ALL: [DeviceClass; 5] = [
        DeviceClass::Gpu,
        DeviceClass::LavapipeMesa25Amd,
        DeviceClass::Lavapipe,
        DeviceClass::LavapipeWithLoopLimit,
        DeviceClass::OtherCpu,
    ];

    /// The class of `device`, whose loops are cut short where `loop_limit`.
    pub fn of(device: &DeviceInfo, loop_limit: bool) -> DeviceClass {
        if device.kind != crate::gpu::DeviceType::Cpu && !device.is_lavapipe() {
            DeviceClass::Gpu
        } else if !device.is_lavapipe() {
            DeviceClass::OtherCpu
        } else if loop_limit {
            DeviceClass::LavapipeWithLoopLimit
        } else if mesa_major(&device.driver_info) == Some(25) && cpu_is_amd() {
            DeviceClass::LavapipeMesa25Amd
        } else {
            DeviceClass::Lavapipe
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            DeviceClass::Gpu => "GPU",
            DeviceClass::LavapipeMesa25Amd => "lavapipe, Mesa 25 on an AMD CPU",
            DeviceClass::Lavapipe => "lavapipe, Mesa 24 or later",
            DeviceClass::LavapipeWithLoopLimit => "lavapipe before Mesa 24 (loop limit)",
            DeviceClass::OtherCpu => "another CPU device",
        }
    }
}

/// A device class's choices where no option is given. Figures are docs/benchmarks/history.md's,
/// by date and commit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Defaults {
    /// The megakernel everywhere: the wavefront lost 2-5x to it on lavapipe (2026-12-01,
    /// `7a44715`: each kernel reloads and stores every path's state through the lanes), cannot run
    /// where loops end early, and is unmeasured on a GPU.
    pub wavefront: bool,
    /// The walk queue on lavapipe whose loops run to their end, for scenes of two to four placed
    /// meshes (1.2-1.4x on the mesh scenes, 2026-12-04, `d1c2c17`); not on a GPU (unmeasured,
    /// and its lanes would need subgroup barriers) nor where loops end early.
    pub walk_queue: bool,
    /// Storage buffers on Mesa 25's lavapipe on an AMD CPU (Zen 4: mesh box 1.09x, mesh under a
    /// sky 1.43x, 2026-12-06, `273e196`); texels everywhere else (Intel Sapphire Rapids: nodes as
    /// storage 0.91x, `b968832`; Mesa 26.2 on the same AMD CPU 0.90x; Mesa 22.3: texels 1.2-2x,
    /// 2026-12-02, `093d897`; an NVIDIA H200: level, 2026-12-04, `3e96a5c`).
    pub walk_records: WalkRecords,
    /// Tiles taken from a counter on CPU devices whose loops run to their end (lavapipe: 1.10x on
    /// the mesh box, the two cores of a 2-core machine 1.99 busy instead of 1.82, 2026-12-05,
    /// `36b0b8f`); not on a GPU, which hands out workgroups as its units free up, nor where loops end early.
    pub take_tiles: bool,
    /// 8x8 everywhere: lavapipe runs a subgroup of 8 lanes as one SIMD thread and the walk queue
    /// is laid out for eight of them; on an NVIDIA H200 no other shape gained more than 3 %
    /// (2026-12-04, `3e96a5c`).
    pub workgroup: Workgroup,
    /// Four-wide nodes everywhere: the eight-wide walk lost on lavapipe (docs/benchmarks.md,
    /// 2026-12-07) and is unmeasured on a GPU.
    pub bvh_width: BvhWidth,
    /// Sorted everywhere: the unsorted shadow walk is unmeasured on a GPU (docs/benchmarks.md
    /// has lavapipe's figure).
    pub shadow_walk: ShadowWalk,
}

impl Defaults {
    pub fn for_class(class: DeviceClass) -> Defaults {
        let base = Defaults {
            wavefront: false,
            walk_queue: false,
            walk_records: WalkRecords::Texels,
            take_tiles: false,
            workgroup: Workgroup::EIGHT_BY_EIGHT,
            bvh_width: BvhWidth::Four,
            shadow_walk: ShadowWalk::Sorted,
        };
        match class {
            DeviceClass::Gpu | DeviceClass::LavapipeWithLoopLimit => base,
            DeviceClass::Lavapipe => Defaults { walk_queue: true, take_tiles: true, ..base },
            DeviceClass::OtherCpu => Defaults { take_tiles: true, ..base },
            DeviceClass::LavapipeMesa25Amd => {
                Defaults { walk_queue: true, take_tiles: true, walk_records: WalkRecords::Storage, ..base }
            }
        }
    }
}

/// What a kernel runs with on a device for a scene: the options applied over the device class's
/// defaults, each checked against what the device and the scene allow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KernelChoices {
    pub wavefront: bool,
    pub walk_queue: Option<WalkQueue>,
    pub walk_records: WalkRecords,
    pub take_tiles: bool,
    pub workgroup: Workgroup,
    pub bvh_width: BvhWidth,
    pub shadow_walk: ShadowWalk,
}

/// The scene facts the choices depend on: the kernel's features and the top level of its BVH.
pub struct SceneShape<'s> {
    pub features: &'s SceneFeatures,
    pub root: Option<&'s WideNode>,
    pub instances: &'s [GpuInstance],
    /// Rays are traced by the device's ray queries: there is no walk to queue.
    pub ray_queries: bool,
}

impl KernelOptions {
    /// The node format of the meshes' and shapes' BVHs on `device` (whose loops are cut short
    /// where `loop_limit`): needed before the scene's data is built, which [`Self::choose`]
    /// reads.
    pub fn bvh_width(&self, device: &DeviceInfo, loop_limit: bool) -> BvhWidth {
        self.bvh_width.unwrap_or(Defaults::for_class(DeviceClass::of(device, loop_limit)).bvh_width)
    }

    /// The choices for `scene` on `device` (whose loops are cut short where `loop_limit`). An
    /// error where an option asks for what cannot run there.
    pub fn choose(&self, device: &DeviceInfo, loop_limit: bool, scene: SceneShape) -> Result<KernelChoices> {
        let defaults = Defaults::for_class(DeviceClass::of(device, loop_limit));
        let workgroup = self.workgroup.unwrap_or(defaults.workgroup);
        let wavefront = self.wavefront.unwrap_or(defaults.wavefront);
        if wavefront && scene.features.media {
            bail!(
                "wavefront=1: the scene has participating media, whose shadow rays pass null boundaries in a loop of their own that only the megakernel runs (shaders/medium.glsl)"
            );
        }
        if wavefront && loop_limit {
            bail!(
                "wavefront=1: {} ends shader loops early, and the wavefront runs only where loops run to their end",
                device.name
            );
        }
        let bvh_width = self.bvh_width(device, loop_limit);
        // The queue walks four-wide nodes alone (walk_queue.glsl): the eight-wide walk goes
        // without it.
        let queue_request = match (self.walk_queue, bvh_width) {
            (Some(QueueRequest::Off), _) | (None, BvhWidth::Eight) => QueueRequest::Off,
            (Some(_), BvhWidth::Eight) => {
                bail!("walk-queue: the walk queue walks four-wide nodes alone; bvh-width=8 walks without it (walk-queue=0)")
            }
            (Some(request), BvhWidth::Four) => request,
            (None, BvhWidth::Four) if defaults.walk_queue => QueueRequest::On,
            (None, BvhWidth::Four) => QueueRequest::Off,
        };
        let walk_queue = match wavefront || scene.ray_queries {
            true => None,
            false => WalkQueue::for_scene(
                queue_request,
                device,
                loop_limit,
                workgroup.invocations(),
                scene.features,
                scene.root,
                scene.instances,
            )?,
        };
        let take_tiles =
            tile_taking::takes_tiles(self.take_tiles, defaults.take_tiles, device, loop_limit, wavefront, workgroup)?;
        let walk_records = self.walk_records.unwrap_or(defaults.walk_records);
        let shadow_walk = self.shadow_walk.unwrap_or(defaults.shadow_walk);
        Ok(KernelChoices { wavefront, walk_queue, walk_records, take_tiles, workgroup, bvh_width, shadow_walk })
    }
}

/// Mesa's major version in a driver's info string ("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)").
fn mesa_major(driver_info: &str) -> Option<u32> {
    let version = driver_info.split("Mesa ").nth(1)?;
    version.split('.').next()?.parse().ok()
}

/// Whether this process runs on an AMD CPU (CPUID's vendor string), where lavapipe runs its
/// kernels.
fn cpu_is_amd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: CPUID leaf 0 exists on every x86_64 CPU and only reads registers.
        #[allow(unused_unsafe)]
        let leaf = unsafe { std::arch::x86_64::__cpuid(0) };
        let vendor: Vec<u8> = [leaf.ebx, leaf.edx, leaf.ecx].iter().flat_map(|r| r.to_le_bytes()).collect();
        vendor == b"AuthenticAMD"
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_option_takes_its_values_and_refuses_others() {
        let mut o = KernelOptions::default();
        o.set_assignment("wavefront=1").unwrap();
        o.set_assignment("walk-queue=barriers").unwrap();
        o.set_assignment("walk-records=storage").unwrap();
        o.set_assignment("take-tiles=0").unwrap();
        o.set_assignment("workgroup=16x8").unwrap();
        o.set_assignment("bvh-width=8").unwrap();
        o.set_assignment("shadow-walk=unsorted").unwrap();
        assert_eq!(
            o,
            KernelOptions {
                wavefront: Some(true),
                walk_queue: Some(QueueRequest::WithBarriers),
                walk_records: Some(WalkRecords::Storage),
                take_tiles: Some(false),
                workgroup: Some(Workgroup { width: 16, height: 8 }),
                bvh_width: Some(BvhWidth::Eight),
                shadow_walk: Some(ShadowWalk::Unsorted),
            }
        );
        for (bad, says) in [
            ("wavefront=yes", "expected 0"),
            ("walk-queue=2", "expected 0"),
            ("walk-records=ssbo", "expected texels"),
            ("take-tiles=on", "expected 0"),
            ("workgroup=12x8", "powers of two"),
            ("bvh-width=16", "expected 4"),
            ("shadow-walk=any", "expected sorted"),
            ("walkqueue=1", "no kernel option 'walkqueue'"),
            ("wavefront", "expected KEY=VALUE"),
        ] {
            let error = o.set_assignment(bad).unwrap_err().to_string();
            assert!(error.contains(bad) && error.contains(says), "{bad}: {error}");
        }
    }

    #[test]
    fn every_option_is_listed_with_its_variable_and_documented_in_help() {
        let help = help();
        for option in &OPTIONS {
            assert!(option.variable.starts_with("CAUSTICA_"), "{}", option.variable);
            assert!(help.contains(option.key) && help.contains(option.variable), "{}", option.key);
            // Every key is one `set` knows.
            let error = KernelOptions::default().set(option.key, "?").unwrap_err().to_string();
            assert!(!error.contains("no kernel option"), "{}: {error}", option.key);
        }
    }

    #[test]
    fn the_defaults_differ_by_class_as_measured() {
        let gpu = Defaults::for_class(DeviceClass::Gpu);
        assert!(!gpu.wavefront && !gpu.walk_queue && !gpu.take_tiles && gpu.walk_records == WalkRecords::Texels);
        let limited = Defaults::for_class(DeviceClass::LavapipeWithLoopLimit);
        assert!(!limited.walk_queue && !limited.take_tiles && limited.walk_records == WalkRecords::Texels);
        let current = Defaults::for_class(DeviceClass::Lavapipe);
        assert!(current.walk_queue && current.take_tiles && current.walk_records == WalkRecords::Texels);
        let amd = Defaults::for_class(DeviceClass::LavapipeMesa25Amd);
        assert!(amd.walk_queue && amd.take_tiles && amd.walk_records == WalkRecords::Storage);
        assert!(DeviceClass::ALL.iter().all(|&c| Defaults::for_class(c).workgroup == Workgroup::EIGHT_BY_EIGHT));
        assert!(DeviceClass::ALL.iter().all(|&c| Defaults::for_class(c).bvh_width == BvhWidth::Four));
        assert!(DeviceClass::ALL.iter().all(|&c| Defaults::for_class(c).shadow_walk == ShadowWalk::Sorted));
    }

    #[test]
    fn mesa_s_major_version_is_read_from_the_driver_info() {
        assert_eq!(mesa_major("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)"), Some(25));
        assert_eq!(mesa_major("Mesa 26.2.6-1 (LLVM 22.1.8)"), Some(26));
        assert_eq!(mesa_major("Mesa 22.3.6 (LLVM 15.0.6)"), Some(22));
        assert_eq!(mesa_major("580.159.04"), None);
        assert_eq!(mesa_major(""), None);
    }

    #[test]
    fn the_cpu_vendor_matches_proc_cpuinfo() {
        // Linux names the vendor in /proc/cpuinfo; elsewhere there is nothing to check against.
        let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") else { return };
        let Some(line) = info.lines().find(|l| l.starts_with("vendor_id")) else { return };
        assert_eq!(cpu_is_amd(), line.contains("AuthenticAMD"), "{line}");
    }
}
