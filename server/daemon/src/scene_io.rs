//! Reading scenes and maps from disk (the planner itself never touches files).

use std::path::{Path, PathBuf};

use crate::error::{Context, Result};
use shift_planner::map::{GridGeometry, LoadedMap, load_ros_map};
use shift_planner::speed::AttributeMap;
use shift_proto::{AttributeDoc, SceneFile};

/// A scene read from a folder: the scene file, the loaded map and where it came from.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// Scene name (the folder's name).
    pub name: String,
    /// The scene file.
    pub scene: SceneFile,
    /// The map.
    pub map: LoadedMap,
    /// Folder.
    pub dir: PathBuf,
}

/// Loads a map_server YAML and its image (resolved relative to the YAML's folder, as map_server does).
pub fn load_map(yaml_path: &Path) -> Result<LoadedMap> {
    let text = std::fs::read_to_string(yaml_path).with_context(|| format!("reading {}", yaml_path.display()))?;
    let dir = yaml_path.parent().map(Path::to_path_buf).unwrap_or_default();
    let map = load_ros_map(&text, |image| {
        let p = dir.join(image);
        std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))
    })
    .with_context(|| format!("loading map {}", yaml_path.display()))?;
    Ok(map)
}

/// Loads `DIR/scene.json` and its map.
pub fn load_scene(dir: &Path) -> Result<LoadedScene> {
    let scene_path = dir.join("scene.json");
    let text = std::fs::read_to_string(&scene_path).with_context(|| format!("reading {}", scene_path.display()))?;
    let scene: SceneFile = serde_json::from_str(&text).with_context(|| format!("parsing {}", scene_path.display()))?;
    let map = load_map(&dir.join(&scene.map))?;
    let name = dir
        .file_name()
        .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned());
    Ok(LoadedScene {
        name,
        scene,
        map,
        dir: dir.to_path_buf(),
    })
}

/// Every folder under `root` holding a scene.json, sorted by name.
pub fn scene_dirs(root: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(root).with_context(|| format!("listing {}", root.display()))? {
        let p = entry?.path();
        if p.join("scene.json").is_file() {
            out.push(p);
        }
    }
    out.sort();
    Ok(out)
}

/// Loads an attribute map for a grid: a `.json` file holds Gaussian blobs ([`AttributeDoc`]); anything else is
/// a grey image (PGM or PNG) of the map's size, A = value / 255.
pub fn load_attribute(path: &Path, geometry: GridGeometry) -> Result<AttributeMap> {
    let bytes = std::fs::read(path).with_context(|| format!("reading attribute {}", path.display()))?;
    let is_json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let map = if is_json {
        let doc: AttributeDoc =
            serde_json::from_slice(&bytes).with_context(|| format!("parsing attribute {}", path.display()))?;
        shift_engine::attribute_map(&doc, geometry)
    } else {
        AttributeMap::from_image_bytes(geometry, &bytes)
    };
    map.with_context(|| format!("attribute {}", path.display()))
}

/// The attribute file a scene names, resolved against its folder.
pub fn scene_attribute_path(scene: &LoadedScene) -> Option<PathBuf> {
    scene.scene.attribute.as_ref().map(|a| scene.dir.join(a))
}
