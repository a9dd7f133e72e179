//! Loading safety: buffer and image URIs resolve only inside the scene file's folder unless
//! `LoadOptions::allow_external_files` is set; only regular files are read; buffers no further
//! than their `byteLength`, images up to `MAX_IMAGE_FILE_BYTES`. Every refusal has a positive
//! control (the same file loads when the rule allows it), so it is the rule that refuses, not a
//! missing file; every error names the scene file, the glTF field and the reason.

use std::path::{Path, PathBuf};

use gltf::json::Value;
use render::scene::{LoadOptions, Scene, MAX_IMAGE_FILE_BYTES};

const ALLOW: LoadOptions = LoadOptions {
    allow_external_files: true,
};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// A fresh `<tmp>/unsafe_uri-<test>/` with `scene/` (the fixture's buffer and image) and
/// `outside/` (copies of both, outside the scene folder). Returns (scene dir, outside dir).
fn fixture(test: &str) -> (PathBuf, PathBuf) {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("unsafe_uri-{test}"));
    let _ = std::fs::remove_dir_all(&root);
    let (scene, outside) = (root.join("scene"), root.join("outside"));
    for d in [&scene, &outside] {
        std::fs::create_dir_all(d).unwrap();
        std::fs::copy(data("tiny.bin"), d.join("tiny.bin")).unwrap();
        std::fs::copy(data("checker.png"), d.join("checker.png")).unwrap();
    }
    (scene, outside)
}

/// Writes the external-file fixture `tiny.gltf`, edited by `edit`, to `dir/name`.
fn write_scene(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let mut v: Value =
        gltf::json::deserialize::from_slice(&std::fs::read(data("tiny.gltf")).unwrap()).unwrap();
    edit(&mut v);
    let path = dir.join(name);
    std::fs::write(&path, gltf::json::serialize::to_vec(&v).unwrap()).unwrap();
    path
}

fn with_buffer_uri(dir: &Path, uri: &str) -> PathBuf {
    let uri = uri.to_owned();
    write_scene(dir, "scene.gltf", move |v| {
        v["buffers"][0]["uri"] = Value::from(uri);
    })
}

fn with_image_uri(dir: &Path, uri: &str) -> PathBuf {
    let uri = uri.to_owned();
    write_scene(dir, "scene.gltf", move |v| {
        v["images"][0]["uri"] = Value::from(uri);
    })
}

/// The error message of loading `path` with `options`; panics if it loads.
fn err(path: &Path, options: &LoadOptions) -> String {
    match Scene::load_with(path, options) {
        Ok(_) => panic!("{} loaded, expected an error", path.display()),
        Err(e) => e.to_string(),
    }
}

/// Asserts `msg` contains every needle.
fn assert_has(msg: &str, needles: &[&str]) {
    for n in needles {
        assert!(msg.contains(n), "'{n}' missing from: {msg}");
    }
}

/// Loads `path` with `options` and checks it is the fixture (5 triangles, 1 texture).
fn assert_loads(path: &Path, options: &LoadOptions) {
    let s = Scene::load_with(path, options)
        .unwrap_or_else(|e| panic!("{} should load: {e}", path.display()));
    assert_eq!(s.mesh().triangle_count(), 5);
    assert_eq!(s.textures().len(), 1);
}

#[test]
fn files_inside_the_folder_load() {
    let (scene, _) = fixture("inside");
    std::fs::create_dir_all(scene.join("sub")).unwrap();
    std::fs::copy(data("tiny.bin"), scene.join("sub/b.bin")).unwrap();
    for uri in [
        "tiny.bin",
        "./tiny.bin",
        "sub/b.bin",
        "sub/../tiny.bin",
        "sub%2Fb.bin",
    ] {
        assert_loads(&with_buffer_uri(&scene, uri), &LoadOptions::default());
    }
    // A file:// URI naming a file inside the folder is fine too.
    let inside = scene.canonicalize().unwrap().join("tiny.bin");
    let uri = format!("file://{}", inside.display());
    assert_loads(&with_buffer_uri(&scene, &uri), &LoadOptions::default());
    assert!(!LoadOptions::default().allow_external_files);
}

#[test]
fn parent_dir_escape_is_refused() {
    let (scene, _) = fixture("dotdot");
    let path = with_buffer_uri(&scene, "../outside/tiny.bin");
    let e = err(&path, &LoadOptions::default());
    assert_has(
        &e,
        &[
            "scene.gltf",
            "buffers[0].uri",
            "../outside/tiny.bin",
            "leaves the scene folder",
            "--allow-external-files",
        ],
    );
    // Control: the file is there, and the option lets it load.
    assert_loads(&path, &ALLOW);
    // Also for images, with the escape after a subfolder.
    std::fs::create_dir_all(scene.join("sub")).unwrap();
    let path = with_image_uri(&scene, "sub/../../outside/checker.png");
    let e = err(&path, &LoadOptions::default());
    assert_has(&e, &["images[0].uri", "leaves the scene folder"]);
    assert_loads(&path, &ALLOW);
}

#[test]
fn absolute_paths_are_refused() {
    let (scene, outside) = fixture("absolute");
    let abs = outside.join("tiny.bin");
    let path = with_buffer_uri(&scene, abs.to_str().unwrap());
    let e = err(&path, &LoadOptions::default());
    assert_has(&e, &["scene.gltf", "buffers[0].uri", "absolute path"]);
    assert_loads(&path, &ALLOW);

    let abs = outside.join("checker.png");
    let path = with_image_uri(&scene, abs.to_str().unwrap());
    let e = err(&path, &LoadOptions::default());
    assert_has(&e, &["images[0].uri", "absolute path"]);
    assert_loads(&path, &ALLOW);

    // From memory.
    let bytes = std::fs::read(&path).unwrap();
    let e = Scene::from_gltf_slice(&bytes, Some(&scene))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_has(&e, &["<memory>", "images[0].uri", "absolute path"]);
    let abs = outside.join("tiny.bin");
    let bytes = std::fs::read(with_buffer_uri(&scene, abs.to_str().unwrap())).unwrap();
    let e = Scene::from_gltf_slice(&bytes, None)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_has(&e, &["<memory>", "buffers[0].uri", "absolute path"]);
}

#[test]
fn file_uris_outside_the_folder_are_refused() {
    let (scene, outside) = fixture("file-uri");
    let uri = format!("file://{}", outside.join("tiny.bin").display());
    let path = with_buffer_uri(&scene, &uri);
    let e = err(&path, &LoadOptions::default());
    assert_has(
        &e,
        &["buffers[0].uri", "outside the scene folder", "tiny.bin"],
    );
    assert_loads(&path, &ALLOW);
    // Other schemes are never fetched.
    let e = err(
        &with_buffer_uri(&scene, "http://example.com/tiny.bin"),
        &ALLOW,
    );
    assert_has(&e, &["buffers[0].uri", "unsupported URI scheme"]);
}

#[cfg(unix)]
#[test]
fn symlinks_out_of_the_folder_are_refused() {
    use std::os::unix::fs::symlink;
    let (scene, outside) = fixture("symlink");
    symlink(outside.join("tiny.bin"), scene.join("link.bin")).unwrap();
    let path = with_buffer_uri(&scene, "link.bin");
    let e = err(&path, &LoadOptions::default());
    assert_has(
        &e,
        &[
            "buffers[0].uri",
            "through a symbolic link",
            "outside the scene folder",
        ],
    );
    assert_loads(&path, &ALLOW);
    // A linked directory leading out is caught the same way.
    symlink(&outside, scene.join("out")).unwrap();
    let path = with_image_uri(&scene, "out/checker.png");
    let e = err(&path, &LoadOptions::default());
    assert_has(&e, &["images[0].uri", "through a symbolic link"]);
    assert_loads(&path, &ALLOW);
    // A link that stays inside is fine.
    symlink(scene.join("tiny.bin"), scene.join("alias.bin")).unwrap();
    assert_loads(
        &with_buffer_uri(&scene, "alias.bin"),
        &LoadOptions::default(),
    );
}

#[cfg(unix)]
#[test]
fn devices_are_refused_even_when_external_files_are_allowed() {
    let (scene, _) = fixture("dev-zero");
    // Today's failure: "/dev/zero" was read until memory ran out.
    let path = with_buffer_uri(&scene, "/dev/zero");
    let e = err(&path, &LoadOptions::default());
    assert_has(&e, &["buffers[0].uri", "absolute path"]);
    let e = err(&path, &ALLOW);
    assert_has(
        &e,
        &[
            "buffers[0].uri",
            "/dev/zero",
            "a character device",
            "not a regular file",
        ],
    );
    let e = err(&with_buffer_uri(&scene, "file:///dev/zero"), &ALLOW);
    assert_has(&e, &["buffers[0].uri", "a character device"]);
    // Through a link inside the folder.
    std::os::unix::fs::symlink("/dev/zero", scene.join("zero.bin")).unwrap();
    let path = with_buffer_uri(&scene, "zero.bin");
    assert_has(
        &err(&path, &LoadOptions::default()),
        &["outside the scene folder"],
    );
    assert_has(&err(&path, &ALLOW), &["a character device"]);
    let path = with_image_uri(&scene, "zero.bin");
    assert_has(
        &err(&path, &ALLOW),
        &["images[0].uri", "a character device"],
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_without_blocking() {
    let (scene, _) = fixture("fifo");
    let fifo = scene.join("pipe.bin");
    let status = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(status.success());
    let path = with_buffer_uri(&scene, "pipe.bin");
    let (tx, rx) = std::sync::mpsc::channel();
    let p = path.clone();
    std::thread::spawn(move || {
        let _ = tx.send(err(&p, &LoadOptions::default()));
    });
    let e = match rx.recv_timeout(std::time::Duration::from_secs(20)) {
        Ok(e) => e,
        Err(_) => {
            // Unblock the reader so the process can end, then fail.
            let _ = std::fs::OpenOptions::new().write(true).open(&fifo);
            panic!("loading a scene whose buffer is a FIFO blocked");
        }
    };
    assert_has(
        &e,
        &["buffers[0].uri", "pipe.bin", "a FIFO", "not a regular file"],
    );
    // The scene file itself may not be a FIFO either.
    let fifo_scene = scene.join("pipe.gltf");
    std::process::Command::new("mkfifo")
        .arg(&fifo_scene)
        .status()
        .unwrap();
    let e = Scene::load(&fifo_scene)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_has(&e, &["pipe.gltf", "a FIFO", "not a regular file"]);
}

#[test]
fn directories_are_refused() {
    let (scene, _) = fixture("directory");
    std::fs::create_dir_all(scene.join("sub")).unwrap();
    let e = err(&with_buffer_uri(&scene, "sub"), &ALLOW);
    assert_has(&e, &["buffers[0].uri", "a directory", "not a regular file"]);
    let e = err(&with_image_uri(&scene, "."), &LoadOptions::default());
    assert_has(&e, &["images[0].uri", "a directory"]);
    // The scene path itself.
    let dir_scene = scene.join("folder.gltf");
    std::fs::create_dir_all(&dir_scene).unwrap();
    let e = Scene::load(&dir_scene).map(|_| ()).unwrap_err().to_string();
    assert_has(&e, &["folder.gltf", "a directory", "not a regular file"]);
}

/// A file of `len` bytes starting with `head`, sparse where the file system allows it.
fn big_file(path: &Path, head: &[u8], len: u64) {
    std::fs::write(path, head).unwrap();
    std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .unwrap()
        .set_len(len)
        .unwrap();
}

#[test]
fn buffers_are_read_up_to_their_byte_length() {
    let (scene, _) = fixture("byte-length");
    // 64 GiB (sparse): reading the whole file would exhaust memory, as "/dev/zero" did.
    let head = std::fs::read(data("tiny.bin")).unwrap();
    big_file(&scene.join("huge.bin"), &head, 64 << 30);
    let t = std::time::Instant::now();
    assert_loads(
        &with_buffer_uri(&scene, "huge.bin"),
        &LoadOptions::default(),
    );
    assert!(t.elapsed().as_secs() < 10, "took {:?}", t.elapsed());
    // A file shorter than byteLength is still an error.
    std::fs::write(scene.join("short.bin"), &head[..100]).unwrap();
    let e = err(
        &with_buffer_uri(&scene, "short.bin"),
        &LoadOptions::default(),
    );
    assert_has(&e, &["buffers[0].byteLength is 384", "only 100 bytes"]);
}

#[test]
fn oversized_images_are_refused() {
    let (scene, _) = fixture("big-image");
    let png = std::fs::read(data("checker.png")).unwrap();
    big_file(&scene.join("big.png"), &png, MAX_IMAGE_FILE_BYTES + 1);
    let e = err(&with_image_uri(&scene, "big.png"), &LoadOptions::default());
    assert_has(
        &e,
        &[
            "images[0].uri",
            &format!("{} bytes", MAX_IMAGE_FILE_BYTES + 1),
            "256 MiB",
        ],
    );
    // Control: the same image at its real size loads.
    std::fs::write(scene.join("small.png"), &png).unwrap();
    assert_loads(
        &with_image_uri(&scene, "small.png"),
        &LoadOptions::default(),
    );
}
