//! Walk through a mesh level with its PVS: the level as glTF with one node per cluster
//! named by its id (`sightline clusters LEVEL.obj -o L.glb`), its `.pvs`
//! (`sightline build LEVEL.obj -o L.pvs`), and the nodes outside the PVS of the camera's
//! cell hidden. Needs a window and a GPU (Bevy's default plugins):
//!
//! ```sh
//! cargo run --release -p bevy_sightline --features viewer --example walk -- L.glb L.pvs [SPEED]
//! ```
//!
//! W/S/A/D walk, arrows turn, Q/E fly down and up; the window title shows the cell and the
//! share of nodes drawn.

use bevy::prelude::*;
use bevy_sightline::{ActivePvs, Axes, PvsAsset, PvsCamera, PvsIds, PvsView, SightlinePlugin};
use std::path::Path;

#[derive(Resource)]
struct Level {
    pvs: Handle<PvsAsset>,
    speed: f32,
    placed: bool,
}

/// An asset path for a file anywhere: the asset root is `/`.
fn asset_path(file: &str) -> String {
    let path = Path::new(file)
        .canonicalize()
        .unwrap_or_else(|e| panic!("{file}: {e}"));
    path.to_string_lossy().trim_start_matches('/').to_owned()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [gltf, pvs, rest @ ..] = &args[..] else {
        eprintln!("usage: walk LEVEL.glb LEVEL.pvs [SPEED units/s]");
        std::process::exit(2);
    };
    let speed: f32 = rest.first().and_then(|s| s.parse().ok()).unwrap_or(5.0);
    let (gltf, pvs) = (asset_path(gltf), asset_path(pvs));
    App::new()
        .add_plugins((
            DefaultPlugins.set(AssetPlugin {
                file_path: "/".into(),
                ..default()
            }),
            SightlinePlugin::default(),
        ))
        .add_systems(
            Startup,
            move |mut commands: Commands, assets: Res<AssetServer>| {
                commands.spawn(WorldAssetRoot(
                    assets.load(GltfAssetLabel::Scene(0).from_asset(gltf.clone())),
                ));
                let pvs: Handle<PvsAsset> = assets.load(pvs.clone());
                commands.insert_resource(ActivePvs(pvs.clone()));
                commands.insert_resource(Level {
                    pvs,
                    speed,
                    placed: false,
                });
                commands.spawn((Camera3d::default(), Transform::default(), PvsCamera));
                commands.spawn((
                    DirectionalLight::default(),
                    Transform::default().looking_to(Vec3::new(-0.3, -1.0, -0.5), Vec3::Y),
                ));
            },
        )
        .add_systems(Update, (start, walk, title))
        .run();
}

/// Once the `.pvs` has loaded, put the camera in the middle of its first cell.
fn start(
    mut level: ResMut<Level>,
    assets: Res<Assets<PvsAsset>>,
    mut camera: Single<&mut Transform, With<PvsCamera>>,
) {
    if level.placed {
        return;
    }
    let Some(b) = assets.get(&level.pvs).and_then(|a| a.pvs().cell_box(0)) else {
        return;
    };
    let centre = [
        (b[0] + b[3]) / 2.0,
        (b[1] + b[4]) / 2.0,
        (b[2] + b[5]) / 2.0,
    ];
    camera.translation = Axes::YUp.to_bevy(centre);
    level.placed = true;
}

fn walk(
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    level: Res<Level>,
    mut camera: Single<&mut Transform, With<PvsCamera>>,
) {
    let dt = time.delta_secs();
    let key = |k: KeyCode| if keys.pressed(k) { 1.0 } else { 0.0 };
    let turn = key(KeyCode::ArrowLeft) - key(KeyCode::ArrowRight);
    let pitch = key(KeyCode::ArrowUp) - key(KeyCode::ArrowDown);
    camera.rotate_y(turn * 1.5 * dt);
    camera.rotate_local_x(pitch * 1.0 * dt);
    let forward = camera.forward().with_y(0.0).normalize_or_zero();
    let right = camera.right().with_y(0.0).normalize_or_zero();
    let step = forward * (key(KeyCode::KeyW) - key(KeyCode::KeyS))
        + right * (key(KeyCode::KeyD) - key(KeyCode::KeyA))
        + Vec3::Y * (key(KeyCode::KeyE) - key(KeyCode::KeyQ));
    camera.translation += step * level.speed * dt;
}

fn title(
    view: Res<PvsView>,
    nodes: Query<&Visibility, With<PvsIds>>,
    mut window: Single<&mut Window>,
) {
    let shown = nodes.iter().filter(|v| **v != Visibility::Hidden).count();
    window.title = match view.cell() {
        Some(cell) => format!("cell {cell}: {shown} of {} nodes drawn", nodes.iter().len()),
        None => "outside every cell: everything drawn".into(),
    };
}
