//! `rt-view cast`: the CSV contract of `docs/command-line.md`, round-tripping numbers, and
//! agreement between `cast --pixels` and `render` on every scene.

mod common;

use common::{read_png, rt_view, scenes_dir, stderr, stdout};
use rt_core::lights::environment::Environment;
use rt_core::render::to_rgb8;

const HEADER: &str = "ox,oy,oz,dx,dy,dz,hit,t,object,primitive,nx,ny,nz";

fn sphere_scene() -> String {
    scenes_dir().join("sphere.ron").to_str().unwrap().to_owned()
}

#[test]
fn cast_prints_the_header_then_one_row_per_ray_in_input_order() {
    // sphere.ron: one sphere of radius 1.2 at the origin.
    // Ray 1 from (0,0,-5) along +z: hits at z = -1.2, t = 3.8, normal (0,0,-1).
    // Ray 2 along (0,0,2): same point, t = 1.9.
    // Ray 3 points away: miss. Ray 4 starts inside: leaves at z = +1.2, t = 1.2, normal (0,0,1).
    let input = "# comment\n0,0,-5,0,0,1\n\n0,0,-5,0,0,2\n0,0,-5,0,0,-1\n0,0,0,0,0,1\n";
    let o = rt_view(&["cast", &sphere_scene()], input);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        stdout(&o),
        format!(
            "{HEADER}\n\
             0,0,-5,0,0,1,1,3.8,0,0,0,0,-1\n\
             0,0,-5,0,0,2,1,1.9,0,0,0,0,-1\n\
             0,0,-5,0,0,-1,0,,,,,,\n\
             0,0,0,0,0,1,1,1.2,0,0,0,0,1\n"
        )
    );
}

#[test]
fn rays_come_from_a_file_or_from_stdin_with_a_dash() {
    let dir = tempfile::tempdir().unwrap();
    let rays = dir.path().join("rays.txt");
    std::fs::write(&rays, "0,0,-5,0,0,1\n").unwrap();
    let from_file = rt_view(&["cast", &sphere_scene(), "--rays", rays.to_str().unwrap()], "");
    let from_dash = rt_view(&["cast", &sphere_scene(), "--rays", "-"], "0,0,-5,0,0,1\n");
    assert!(from_file.status.success() && from_dash.status.success());
    assert_eq!(stdout(&from_file), stdout(&from_dash));
    assert_eq!(stdout(&from_file).lines().count(), 2);
}

#[test]
fn printed_numbers_round_trip_to_the_values_the_library_computes() {
    let scene = rt_core::load_scene(&scenes_dir().join("showcase.ron")).unwrap();
    // Awkward rays: non-representable decimals, tiny and huge components.
    let input = "0.1,4.2,-9.5,0.013,-0.31,0.7\n1e-7,3.3333333,-9,0.2,-0.4,1\n-3,1.1,-20,1e-5,0,1\n123.456,7,8,-0.3,-0.2,-0.9\n";
    let o = rt_view(&["cast", scenes_dir().join("showcase.ron").to_str().unwrap()], input);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let mut hits = 0;
    for (line, row) in input.lines().zip(out.lines().skip(1)) {
        let ray = rt_view::commands::cast::parse_ray_line(line).unwrap().unwrap();
        let cols: Vec<&str> = row.split(',').collect();
        assert_eq!(cols.len(), 13, "{row}");
        let num = |i: usize| cols[i].parse::<rt_core::Real>().unwrap();
        assert_eq!([num(0), num(1), num(2)], ray.origin.to_array(), "{row}");
        assert_eq!([num(3), num(4), num(5)], ray.dir.to_array(), "{row}");
        match scene.scene.cast(&ray) {
            Some(h) => {
                hits += 1;
                assert_eq!(cols[6], "1");
                assert_eq!(num(7).to_bits(), h.t.to_bits(), "t of {row}");
                assert_eq!(
                    (cols[8].parse::<usize>().unwrap(), cols[9].parse::<usize>().unwrap()),
                    (h.object, h.primitive)
                );
                assert_eq!([num(10), num(11), num(12)], h.normal.to_array());
                assert!((h.normal.length() - 1.0).abs() < 1e-5);
            }
            None => assert_eq!(&cols[6..], ["0", "", "", "", "", "", ""]),
        }
    }
    assert!(hits >= 3, "the test rays should mostly hit: {out}");
}

#[test]
fn a_malformed_line_is_an_error_naming_it_and_nothing_is_printed() {
    let o = rt_view(&["cast", &sphere_scene()], "0,0,-5,0,0,1\n# ok\n0,0,-5,0,zero,1\n");
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stdout(&o), "");
    assert_eq!(stderr(&o).trim(), "error: <stdin>:3: dy = \"zero\" is not a number");

    let dir = tempfile::tempdir().unwrap();
    let rays = dir.path().join("r.txt");
    std::fs::write(&rays, "1,2,3\n").unwrap();
    let o = rt_view(&["cast", &sphere_scene(), "--rays", rays.to_str().unwrap()], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("r.txt:1: expected 6 comma-separated numbers"), "{}", stderr(&o));
    assert_eq!(stdout(&o), "");
}

#[test]
fn a_ray_leaving_a_surface_does_not_hit_it_again_at_its_origin() {
    // Origin on the sphere's surface (radius 1.2), pointing out: no hit.
    // Pointing in: the far side, t = 2.4 along the unit direction.
    let o = rt_view(&["cast", &sphere_scene()], "0,0,-1.2,0,0,-1\n0,0,-1.2,0,0,1\n1.2,0,0,0,1,0\n");
    let rows: Vec<String> = stdout(&o).lines().skip(1).map(str::to_owned).collect();
    assert_eq!(rows[0], "0,0,-1.2,0,0,-1,0,,,,,,");
    assert!(rows[1].starts_with("0,0,-1.2,0,0,1,1,2.4,0,0,"), "{}", rows[1]);
    // Tangent ray along the surface from a point on it: nothing else to hit.
    assert_eq!(rows[2], "1.2,0,0,0,1,0,0,,,,,,");
}

/// `cast --pixels` on every scene: one row per pixel, in row-major order, and
/// each pixel's colour in `render` is the colour of the object `cast` hit.
#[test]
fn cast_pixels_works_on_every_scene_and_agrees_with_render() {
    let (w, h) = (40u32, 30u32);
    let mut scenes: Vec<_> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 8, "{scenes:?}");
    let dir = tempfile::tempdir().unwrap();
    for path in scenes {
        let name = path.display().to_string();
        let scene = rt_core::load_scene(&path).unwrap();
        let o =
            rt_view(&["cast", &name, "--pixels", "--width", &w.to_string(), "--height", &h.to_string()], "");
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let png = dir.path().join("p.png");
        let r = rt_view(
            &[
                "render",
                &name,
                "-o",
                png.to_str().unwrap(),
                "--width",
                &w.to_string(),
                "--height",
                &h.to_string(),
                "--spp",
                "1",
            ],
            "",
        );
        assert!(r.status.success(), "{name}: {}", stderr(&r));
        let img = read_png(&png);

        let out = stdout(&o);
        let mut lines = out.lines();
        assert_eq!(lines.next(), Some(format!("px,py,{HEADER}").as_str()));
        let rows: Vec<&str> = lines.collect();
        assert_eq!(rows.len(), (w * h) as usize, "{name}");
        let mut hits = 0;
        for (i, row) in rows.iter().enumerate() {
            let cols: Vec<&str> = row.split(',').collect();
            let (px, py) = ((i as u32) % w, (i as u32) / w);
            assert_eq!((cols[0], cols[1]), (px.to_string().as_str(), py.to_string().as_str()), "{name}");
            // Without lights a hit shows its material's flat colour; with
            // lights or global illumination it is shaded, so only misses are
            // predictable.
            let lit = scene.scene.effect_plan(&scene.settings.effects).shading;
            let expected = if cols[8] == "1" {
                hits += 1;
                let object: usize = cols[10].parse().unwrap();
                (!lit).then(|| to_rgb8(scene.scene.object_material(object).color))
            } else {
                // A constant background is the same in every direction; what
                // a miss shows of an environment map depends on its ray.
                match scene.scene.environment() {
                    Environment::Constant(c) => {
                        Some(scene.settings.display.encode(*c, scene.settings.color_space))
                    }
                    Environment::Map(_) => None,
                }
            };
            if let Some(expected) = expected {
                assert_eq!(img.get_pixel(px, py).0, expected, "{name} pixel ({px},{py})");
            }
        }
        assert!(hits > 0, "{name}: the camera sees nothing");
    }
}
