mod common;
use phri_depth::*;
#[test]
fn dump() {
    let k = Intrinsics::default();
    let pose = CameraPose::paper_default();
    let s = common::scene();
    let mut r = Renderer::new(k, pose, RenderOptions::default()).unwrap();
    let mut f = vec![0u16; k.pixel_count()];
    r.render(&s.all, &s.boxes, s.floor_z, &mut f).unwrap();
    let mut sf = SelfFilter::new(k, pose, SelfFilterParams::default()).unwrap();
    let mut g = f.clone();
    sf.apply(&s.robot, &mut g).unwrap();
    for (name, img) in [
        ("/tmp/depth_scene.png", &f),
        ("/tmp/depth_filtered.png", &g),
    ] {
        let bytes: Vec<u8> = img
            .iter()
            .map(|&v| {
                if v == 0 {
                    0
                } else {
                    (255.0 - (v as f64 - 500.0) / 4000.0 * 230.0).clamp(0.0, 255.0) as u8
                }
            })
            .collect();
        let file = std::fs::File::create(name).unwrap();
        let mut e = ::png::Encoder::new(std::io::BufWriter::new(file), k.width, k.height);
        e.set_color(::png::ColorType::Grayscale);
        e.set_depth(::png::BitDepth::Eight);
        let mut w = e.write_header().unwrap();
        w.write_image_data(&bytes).unwrap();
    }
}
