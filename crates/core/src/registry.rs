//! The one registry of methods: each is named once here, with its family, its paper, a
//! one-line summary, whether it is conservative and the knobs it takes. User settings
//! ([`MethodOptions`]: CLI flags, Python keywords, the server's options, a `.pvs`
//! header) are turned into a family's typed options by [`Method::options`], the one
//! place where knobs are validated.

use crate::MethodError;
use serde::{Deserialize, Serialize};

/// A family of methods: the papers one crate or module implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Décoret, Debunne & Sillion 2003 (and Wonka et al. 2000 as its method 1).
    Erosion,
    /// Koltun, Chrysanthou & Cohen-Or 2001.
    DualRay,
    /// Durand, Drettakis, Thollot & Puech 2000.
    ExtProj,
    /// The sampled visible set (survey §7.6): the ground truth, not conservative.
    Sampled,
    /// Teller & Séquin 1991: cells and portals of a BSP level (`sightline-portals`).
    Portals,
    /// Schaufler, Dorsey, Décoret & Sillion 2000: volumetric visibility with occluder
    /// fusion on the voxels of a mesh level (`sightline-autocells`).
    Volumetric,
    /// No culling at all.
    Baseline,
}

/// The kinds of scene with a cell layout of their own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneKind {
    /// Buildings and any scene given a cells file (viewcell boxes).
    City,
    /// A Quake `.bsp`: its leaves are the cells.
    Bsp,
    /// A mesh level (`.obj`, `.gltf`, `.glb`): automatic cells and walkable viewcells.
    Mesh,
}

/// A knob a method takes: its key (for `--set key=value`, Python keywords and the
/// `.pvs` header) and what it means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Knob {
    pub key: &'static str,
    pub help: &'static str,
}

const RESOLUTION: Knob = Knob {
    key: "resolution",
    help: "pixels per side of the method's maps (`--resolution`)",
};
const BINS: Knob = Knob {
    key: "resolution",
    help: "azimuth bins of the polar occlusion maps, 8..=1048576 (`--resolution`)",
};
const SEED: Knob = Knob {
    key: "seed_rays",
    help: "true|false: seed rays mark objects they meet first (saves tests, same PVS)",
};
const VO: Knob = Knob {
    key: "virtual_occluders",
    help: "true|false: per-cell virtual occluders tested before the kd-nodes",
};
const HIDDEN: Knob = Knob {
    key: "hidden_boxes",
    help: "true|false: boxes already proven hidden join the occluders of later tests",
};
const SWEEP: Knob = Knob {
    key: "sweep",
    help: "true|false: run the occlusion sweep (`--sweep`)",
};
const PLANES: Knob = Knob {
    key: "planes",
    help: "sweep planes, 1..=256 (`--planes`)",
};
const SAMPLES: Knob = Knob {
    key: "samples",
    help: "viewpoints per cell (`--samples`)",
};

/// The methods, selected by name everywhere (`--method`, the library, the server, the
/// `.pvs` header).
///
/// ```
/// use sightline_core::Method;
/// let m: Method = "dual-ray".parse().unwrap();
/// assert_eq!(m, Method::DualRay);
/// assert_eq!(m.name(), "dual-ray");
/// assert!(!Method::Sampled.is_conservative());
/// assert!("dual_ray".parse::<Method>().unwrap_err().to_string().contains("known: erosion"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Erosion of the fused occluders by the shaft-supporting segment, occludees shrunk
    /// (Décoret et al. 2003, method 4).
    Erosion,
    /// Occluders eroded by the supporting segments, occludees as they are (method 3).
    ErosionSegment,
    /// Occluders eroded by the whole cell (method 2).
    ErosionCell,
    /// Occluders shrunk by the cell's bounding disc (Wonka et al. 2000; method 1).
    ShrinkSphere,
    /// `erosion` with X-sampling of the cell (erosion paper §7.1).
    ErosionRays,
    /// Hierarchical cell-to-cell tests in a discretized dual ray space (Koltun et al. 2001).
    DualRay,
    /// The exact analytic planar algorithm of the same paper (§5.1).
    DualRayExact,
    /// Extended projections with extended depth maps (Durand et al. 2000).
    ExtProj,
    /// Leaf PVS through portal sequences a line can stab, faces no stabbing line
    /// reaches dropped (Teller & Séquin 1991; BSP levels only).
    Portals,
    /// The cheap flood bound of `portals` (always contains it).
    PortalsFast,
    /// Walkable viewcells of a mesh level, volumetric occlusion with occluder fusion
    /// intersected with the portal flood (Schaufler et al. 2000; mesh levels only).
    Volumetric,
    /// The sampled visible set: aggressive, NOT conservative (the ground truth).
    Sampled,
    /// Every object: the no-culling baseline.
    All,
}

/// Every method name, in the order of [`Method::ALL`].
pub const METHOD_NAMES: &[&str] = &NAMES;

const NAMES: [&str; Method::ALL.len()] = {
    let mut names = [""; Method::ALL.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = Method::ALL[i].name();
        i += 1;
    }
    names
};

impl Method {
    /// Every method, in the order of the README's method table.
    pub const ALL: [Method; 13] = [
        Method::Erosion,
        Method::ErosionSegment,
        Method::ErosionCell,
        Method::ShrinkSphere,
        Method::ErosionRays,
        Method::DualRay,
        Method::DualRayExact,
        Method::ExtProj,
        Method::Portals,
        Method::PortalsFast,
        Method::Volumetric,
        Method::Sampled,
        Method::All,
    ];

    /// The name the method is selected by.
    pub const fn name(self) -> &'static str {
        match self {
            Method::Erosion => "erosion",
            Method::ErosionSegment => "erosion-segment",
            Method::ErosionCell => "erosion-cell",
            Method::ShrinkSphere => "shrink-sphere",
            Method::ErosionRays => "erosion-rays",
            Method::DualRay => "dual-ray",
            Method::DualRayExact => "dual-ray-exact",
            Method::ExtProj => "ext-proj",
            Method::Portals => "portals",
            Method::PortalsFast => "portals-fast",
            Method::Volumetric => "volumetric",
            Method::Sampled => "sampled",
            Method::All => "all",
        }
    }

    /// The family that implements the method.
    pub const fn family(self) -> Family {
        match self {
            Method::Erosion
            | Method::ErosionSegment
            | Method::ErosionCell
            | Method::ShrinkSphere
            | Method::ErosionRays => Family::Erosion,
            Method::DualRay | Method::DualRayExact => Family::DualRay,
            Method::ExtProj => Family::ExtProj,
            Method::Portals | Method::PortalsFast => Family::Portals,
            Method::Volumetric => Family::Volumetric,
            Method::Sampled => Family::Sampled,
            Method::All => Family::Baseline,
        }
    }

    /// The paper and section the method comes from.
    pub const fn paper(self) -> &'static str {
        match self {
            Method::Erosion => "Décoret, Debunne & Sillion 2003, method 4",
            Method::ErosionSegment => "Décoret, Debunne & Sillion 2003, method 3",
            Method::ErosionCell => "Décoret, Debunne & Sillion 2003, method 2",
            Method::ShrinkSphere => "Wonka, Wimmer & Schmalstieg 2000 (erosion paper, method 1)",
            Method::ErosionRays => "Décoret, Debunne & Sillion 2003, §7.1",
            Method::DualRay => "Koltun, Chrysanthou & Cohen-Or 2001, §5.2",
            Method::DualRayExact => "Koltun, Chrysanthou & Cohen-Or 2001, §5.1",
            Method::ExtProj => "Durand, Drettakis, Thollot & Puech 2000",
            Method::Portals | Method::PortalsFast => {
                "Teller & Séquin 1991; the course's cells-and-portals part (Find_Visible_Cells)"
            }
            Method::Volumetric => {
                "Schaufler, Dorsey, Décoret & Sillion 2000; the visibility course §7.1"
            }
            Method::Sampled => "visibility survey §7.6 (aggressive sampling)",
            Method::All => "—",
        }
    }

    /// What the method does, in one line (`--help`, `info`).
    pub const fn summary(self) -> &'static str {
        match self {
            Method::Erosion => "fused occluders eroded by the shaft-supporting segment, occludees shrunk",
            Method::ErosionSegment => "occluders eroded by the supporting segments, occludees as they are",
            Method::ErosionCell => "occluders eroded by the whole cell",
            Method::ShrinkSphere => "occluders shrunk by the cell's bounding disc",
            Method::ErosionRays => "erosion with X-sampled occludees (rays)",
            Method::DualRay => "kd-tree of occludees tested cell-to-object in a discretized dual ray space",
            Method::DualRayExact => "the exact analytic planar dual-ray test (reference for dual-ray)",
            Method::ExtProj => "extended projections on six planes with extended depth maps (--sweep: occlusion sweep)",
            Method::Portals => "BSP leaves and portals: leaf PVS through stabbable portal sequences (separating planes), faces no stabbing line reaches dropped",
            Method::PortalsFast => "BSP leaves and portals: the cheap portal flood (front/back tests only), always contains portals",
            Method::Volumetric => "mesh levels: walkable viewcells, clusters hidden by opaque voxels, closed faces and planar patches (volumetric occlusion), within the portal flood",
            Method::Sampled => "the sampled visible set: NOT conservative, the ground truth",
            Method::All => "every object: the no-culling baseline",
        }
    }

    /// Whether the method applies to a kind of scene: the portal family needs a level
    /// (a BSP's leaves, or a mesh level's automatic cells), `volumetric` a mesh level;
    /// the others take any scene with a cells file.
    pub const fn works_on(self, kind: SceneKind) -> bool {
        match self.family() {
            Family::Portals => matches!(kind, SceneKind::Bsp | SceneKind::Mesh),
            Family::Volumetric => matches!(kind, SceneKind::Mesh),
            _ => matches!(kind, SceneKind::City | SceneKind::Mesh),
        }
    }

    /// Whether the method's PVS always contains every visible object (`all` trivially
    /// does; `sampled` does not).
    pub const fn is_conservative(self) -> bool {
        !matches!(self, Method::Sampled)
    }

    /// The knobs the method takes.
    pub const fn knobs(self) -> &'static [Knob] {
        match self.family() {
            Family::Erosion => &[BINS],
            Family::DualRay => match self {
                Method::DualRayExact => &[SEED, VO, HIDDEN],
                _ => &[RESOLUTION, SEED, VO, HIDDEN],
            },
            Family::ExtProj => &[RESOLUTION, SWEEP, PLANES],
            Family::Sampled => &[RESOLUTION, SAMPLES],
            Family::Portals | Family::Volumetric | Family::Baseline => &[],
        }
    }

    /// The typed options of the method from user settings, validated. Settings the
    /// method has no knob for are ignored, as they always were (one `--resolution` may
    /// be given to a bench of several methods); a value out of a knob's range is an error.
    pub fn options(self, s: &MethodOptions) -> Result<Options, MethodError> {
        let bad = |message: String| MethodError::BadOption {
            method: self.name(),
            message,
        };
        let mut o = match self.family() {
            Family::Erosion => {
                if let Some(b) = s.resolution_px {
                    if !(8..=1 << 20).contains(&b) {
                        return Err(bad(format!(
                            "resolution {b} out of range (8..=1048576 azimuth bins)"
                        )));
                    }
                }
                Options::Erosion(ErosionOptions {
                    azimuth_bins: s.resolution_px,
                })
            }
            Family::DualRay => {
                let resolution_px = match self {
                    Method::DualRay => {
                        if let Some(r) = s.resolution_px {
                            if r == 0 || r > 1 << 20 {
                                return Err(bad(format!(
                                    "resolution {r} out of range (1..=1048576)"
                                )));
                            }
                        }
                        s.resolution_px
                    }
                    _ => None,
                };
                Options::DualRay(DualRayOptions {
                    resolution_px,
                    ..DualRayOptions::default()
                })
            }
            Family::ExtProj => Options::ExtProj(ExtProjOptions {
                resolution_px: s.resolution_px,
                sweep: s.sweep,
                planes: s.planes,
            }),
            Family::Sampled => {
                if s.resolution_px == Some(0) {
                    return Err(bad("resolution must be positive".into()));
                }
                if s.samples == Some(0) {
                    return Err(bad("samples must be positive".into()));
                }
                Options::Sampled(SampledOptions {
                    resolution_px: s.resolution_px,
                    samples: s.samples,
                })
            }
            Family::Portals | Family::Volumetric | Family::Baseline => Options::None,
        };
        for (key, value) in &s.set {
            o.set(self, key, value).map_err(bad)?;
        }
        Ok(o)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = MethodError;
    fn from_str(s: &str) -> Result<Self, MethodError> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| MethodError::Unknown(s.to_string()))
    }
}

/// What a family's constructor accepts: a [`Method`], or its name.
pub trait IntoMethod {
    fn into_method(self) -> Result<Method, MethodError>;
}

impl IntoMethod for Method {
    fn into_method(self) -> Result<Method, MethodError> {
        Ok(self)
    }
}

impl<T: AsRef<str> + ?Sized> IntoMethod for &T {
    fn into_method(self) -> Result<Method, MethodError> {
        self.as_ref().parse()
    }
}

/// User settings, as the CLI, the Python module and the server take them. The common
/// flags have fields; any knob of [`Method::knobs`] can be given by key in `set`.
/// [`Method::options`] turns them into the method's typed [`Options`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodOptions {
    /// `--resolution`: the method's resolution knob (method default if None).
    pub resolution_px: Option<u32>,
    /// `--sweep` (`ext-proj`).
    pub sweep: bool,
    /// `--planes` (`ext-proj --sweep`).
    pub planes: Option<u32>,
    /// `--samples` (`sampled`).
    pub samples: Option<u32>,
    /// `--set key=value`: any knob by its key, applied after the fields above.
    #[serde(default)]
    pub set: Vec<(String, String)>,
}

/// The typed, validated options of one method.
#[derive(Clone, Debug, PartialEq)]
pub enum Options {
    Erosion(ErosionOptions),
    DualRay(DualRayOptions),
    ExtProj(ExtProjOptions),
    Sampled(SampledOptions),
    /// A method without knobs.
    None,
}

/// Options of the erosion family.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErosionOptions {
    /// Azimuth bins of the fine polar maps (family default if None).
    pub azimuth_bins: Option<u32>,
}

/// Options of the dual-ray family. The three switches change the time, never the PVS.
#[derive(Clone, Debug, PartialEq)]
pub struct DualRayOptions {
    /// Ray-space resolution per side (`dual-ray` only; family default if None).
    pub resolution_px: Option<u32>,
    pub seed_rays: bool,
    pub virtual_occluders: bool,
    pub hidden_boxes: bool,
}

impl Default for DualRayOptions {
    fn default() -> Self {
        DualRayOptions {
            resolution_px: None,
            seed_rays: true,
            virtual_occluders: false,
            hidden_boxes: true,
        }
    }
}

/// Options of extended projections.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExtProjOptions {
    /// Depth-map resolution, rounded up to a power of two in 8..=4096 (default if None).
    pub resolution_px: Option<u32>,
    pub sweep: bool,
    /// Sweep planes, clamped to 1..=256 (default if None).
    pub planes: Option<u32>,
}

/// Options of the sampled ground truth.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SampledOptions {
    pub resolution_px: Option<u32>,
    pub samples: Option<u32>,
}

fn parse_bool(key: &str, v: &str) -> Result<bool, String> {
    match v {
        "true" | "on" | "1" | "yes" => Ok(true),
        "false" | "off" | "0" | "no" => Ok(false),
        _ => Err(format!("{key}: expected true or false, got '{v}'")),
    }
}

fn parse_u32(key: &str, v: &str) -> Result<u32, String> {
    v.parse()
        .map_err(|_| format!("{key}: expected a whole number, got '{v}'"))
}

impl Options {
    /// Set one knob of `method` by key (`--set key=value`).
    fn set(&mut self, method: Method, key: &str, value: &str) -> Result<(), String> {
        let known = || {
            let keys: Vec<&str> = method.knobs().iter().map(|k| k.key).collect();
            if keys.is_empty() {
                format!("takes no options (got '{key}')")
            } else {
                format!("unknown option '{key}' (known: {})", keys.join(", "))
            }
        };
        if !method.knobs().iter().any(|k| k.key == key) {
            return Err(known());
        }
        let resolution = || -> Result<u32, String> {
            let r = parse_u32(key, value)?;
            let mut probe = MethodOptions {
                resolution_px: Some(r),
                ..MethodOptions::default()
            };
            probe.set.clear();
            method.options(&probe).map_err(|e| e.to_string())?;
            Ok(r)
        };
        match (self, key) {
            (Options::Erosion(o), "resolution") => o.azimuth_bins = Some(resolution()?),
            (Options::DualRay(o), "resolution") => o.resolution_px = Some(resolution()?),
            (Options::DualRay(o), "seed_rays") => o.seed_rays = parse_bool(key, value)?,
            (Options::DualRay(o), "virtual_occluders") => {
                o.virtual_occluders = parse_bool(key, value)?
            }
            (Options::DualRay(o), "hidden_boxes") => o.hidden_boxes = parse_bool(key, value)?,
            (Options::ExtProj(o), "resolution") => o.resolution_px = Some(resolution()?),
            (Options::ExtProj(o), "sweep") => o.sweep = parse_bool(key, value)?,
            (Options::ExtProj(o), "planes") => o.planes = Some(parse_u32(key, value)?),
            (Options::Sampled(o), "resolution") => o.resolution_px = Some(resolution()?),
            (Options::Sampled(o), "samples") => {
                let s = parse_u32(key, value)?;
                if s == 0 {
                    return Err("samples must be positive".into());
                }
                o.samples = Some(s)
            }
            _ => return Err(known()),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_is_named_once_and_parses_back() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>().unwrap(), m);
            assert!(!m.summary().is_empty() && !m.paper().is_empty());
        }
        let mut names = METHOD_NAMES.to_vec();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Method::ALL.len());
    }

    #[test]
    fn knobs_are_set_by_key_and_validated() {
        let s = |k: &str, v: &str| MethodOptions {
            set: vec![(k.into(), v.into())],
            ..MethodOptions::default()
        };
        let o = Method::DualRay
            .options(&s("virtual_occluders", "true"))
            .unwrap();
        assert!(matches!(
            o,
            Options::DualRay(DualRayOptions {
                virtual_occluders: true,
                ..
            })
        ));
        let e = Method::Erosion.options(&s("sweep", "true")).unwrap_err();
        assert!(e.to_string().contains("unknown option 'sweep'"), "{e}");
        let e = Method::Erosion.options(&s("resolution", "4")).unwrap_err();
        assert!(e.to_string().contains("out of range"), "{e}");
        let e = Method::All.options(&s("resolution", "4")).unwrap_err();
        assert!(e.to_string().contains("takes no options"), "{e}");
        let e = Method::DualRay
            .options(&s("seed_rays", "maybe"))
            .unwrap_err();
        assert!(e.to_string().contains("expected true or false"), "{e}");
        // Common flags a method has no knob for are ignored (a bench passes one
        // `--resolution` to several methods).
        let r = MethodOptions {
            resolution_px: Some(4),
            ..MethodOptions::default()
        };
        assert_eq!(Method::All.options(&r).unwrap(), Options::None);
    }
}
