//! Each scene's relume settings, written as `scenes[0].extras.relume`.

/// A scene's relume settings, written as `scenes[0].extras.relume` (read by
/// `relume_bake::settings`, documented in docs/FORMATS.md). Every scene states all of them,
/// so that its bake does not move when the defaults (sized from the bounds) change.
///
/// The values are first picks: L_max grows with the scene (0.15 m in the 0.55 m Cornell
/// box, 1 m in the 8 m classroom); tau is a third of L_max or a little less, so rho(L_max)
/// is 0.95 or more and the cut at L_max is small; texel densities put 70 to 130 texels
/// across each scene's largest surface. The Cornell scenes' ambient is fitted to the path
/// tracer (see their constants); the others keep beta 0.3 and no ambient until they are.
#[derive(Clone, Copy)]
pub(super) struct Settings {
    /// Ambient irradiance, lux.
    pub(super) ambient: [f64; 3],
    pub(super) beta: f64,
    /// Lightmap texels per metre.
    pub(super) texel_density: f64,
    /// Obscurance tau, metres.
    pub(super) tau: f64,
    /// Obscurance L_max, metres.
    pub(super) l_max: f64,
    /// Where lights may move, for the light path maps (000 §3.2.1): a box (min, max corners,
    /// metres) and its test-point count; None leaves the lights where they stand.
    pub(super) light_region: Option<([f64; 3], [f64; 3], u32)>,
    /// Delta-l of 000 §3.4, square metres.
    pub(super) light_area: f64,
}

/// Fitted against the path tracer (`relume run scenes/cornell.gltf --ambient 1 --beta 0`,
/// docs/BENCHMARKS.md): the least-squares ambient is 0.99 lux with W = 1 and 1.06 with the
/// obscurances; the beta term alone fits worse (its 1/r^2 and spot cone put indirect light
/// where the light points, not where it bounces), so it is off.
pub(super) const CORNELL_SETTINGS: Settings = Settings {
    ambient: [1.0; 3],
    beta: 0.0,
    texel_density: 128.0,
    tau: 0.05,
    l_max: 0.15,
    // Under the ceiling around the spot (x, z within 15 cm of the published light's centre,
    // 1 to 15 cm under the ceiling, where the spot hangs); the published light's
    // 130 x 105 mm as its area.
    light_region: Some(([-0.15, 0.4, -0.43], [0.15, 0.54, -0.13], 64)),
    light_area: 0.01365,
};

/// The same fit on the Fig. 9 failure case: its light has 1/230 of `cornell`'s power.
pub(super) const CORNELL_WALL_LIGHT_SETTINGS: Settings = Settings { ambient: [0.0033; 3], ..CORNELL_SETTINGS };

pub(super) const OCCLUDER_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 32.0, tau: 0.15, l_max: 0.5, light_region: None, light_area: 0.0 };

pub(super) const TABLE_CHAIR_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 24.0, tau: 0.2, l_max: 0.6, light_region: None, light_area: 0.0 };

/// The scale scene: the classroom's, at 8 texels a metre (about 1.5 M covered texels at 10 x 10
/// bays), its lights where they stand.
pub(super) const SCALE_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 8.0, tau: 0.3, l_max: 1.0, light_region: None, light_area: 0.0 };

pub(super) const CLASSROOM_SETTINGS: Settings = Settings {
    ambient: [0.0; 3],
    beta: 0.3,
    texel_density: 16.0,
    tau: 0.3,
    l_max: 1.0,
    // Along the centre aisle under the ceiling, where the three spots hang, 1.5 m either side.
    light_region: Some(([-1.5, 2.5, -3.0], [1.5, 2.95, 3.0], 64)),
    light_area: 0.0,
};

/// The maze: no ambient light (light clouds model it all), the obscurance's range a corridor's
/// width, texels 6 cm; light path maps' region over the corridors at the point light's height.
pub(super) const MAZE_SETTINGS: Settings = Settings {
    ambient: [0.0; 3],
    beta: 0.3,
    texel_density: 16.0,
    tau: 0.1,
    l_max: 0.5,
    light_region: Some(([-2.0, 0.3, -2.0], [2.0, 0.45, 2.0], 64)),
    light_area: 0.0,
};

/// The glossy enclosure: as the maze, texels 4 cm.
pub(super) const GLOSSY_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 24.0, tau: 0.1, l_max: 0.4, light_region: None, light_area: 0.0 };

/// Levels of 2 m blocks: no ambient light (MRT models all indirect light), texels 12.5 cm.
pub(super) const BLOCKS_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 8.0, tau: 0.5, l_max: 1.5, light_region: None, light_area: 0.0 };

/// The courtyard: no ambient light (the sky is its own, and the local-light methods model the
/// lamps' indirect light), texels 8 cm, the obscurance's range a third of the walls' height.
pub(super) const COURTYARD_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 12.0, tau: 0.25, l_max: 0.8, light_region: None, light_area: 0.0 };

/// The sunroom: no ambient light (the sun's bounce is its indirect light), texels 8 cm, the
/// obscurance's range about a third of the room's height.
pub(super) const SUNROOM_SETTINGS: Settings =
    Settings { ambient: [0.0; 3], beta: 0.3, texel_density: 12.0, tau: 0.25, l_max: 0.8, light_region: None, light_area: 0.0 };
