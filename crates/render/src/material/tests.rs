//! Unit tests of the BSDFs: reciprocity, adjointness, sample/eval/pdf consistency, delta lobes,
//! the glTF mapping and input sanitisation. Statistical tests live in `tests/bsdf_chi2.rs` and
//! `tests/bsdf_energy.rs`.

use super::*;
use crate::warp::sample_uniform_sphere;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

fn random_dir(rng: &mut Pcg64) -> Vec3A {
    sample_uniform_sphere(Vec2::new(rng.random(), rng.random()))
}

fn rel_close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1e-6)
}

fn rel_close3(a: Vec3, b: Vec3, tol: f32) -> bool {
    rel_close(a.x, b.x, tol) && rel_close(a.y, b.y, tol) && rel_close(a.z, b.z, tol)
}

/// Every non-delta BSDF exercised by the unit tests.
fn glossy_bsdfs() -> Vec<(&'static str, Bsdf)> {
    let c = Vec3::new(0.9, 0.6, 0.3);
    vec![
        ("lambertian", Bsdf::lambertian(c)),
        ("conductor a=0.05", Bsdf::rough_conductor(c, 0.05)),
        ("conductor a=0.3", Bsdf::rough_conductor(c, 0.3)),
        ("conductor a=1", Bsdf::rough_conductor(c, 1.0)),
        ("dielectric a=0.1", Bsdf::rough_dielectric(1.5, 0.1, c)),
        ("dielectric a=0.5", Bsdf::rough_dielectric(1.5, 0.5, c)),
        (
            "dielectric a=0.3 eta<1",
            Bsdf::rough_dielectric(0.7, 0.3, c),
        ),
    ]
}

#[test]
fn reflection_is_reciprocal() {
    let mut r = rng(1);
    for (name, bsdf) in glossy_bsdfs() {
        for _ in 0..2000 {
            let (a, b) = (random_dir(&mut r), random_dir(&mut r));
            if a.z * b.z <= 0.0 {
                continue; // transmission is checked by `transmission_is_adjoint`
            }
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let (fab, fba) = (bsdf.eval(a, b, mode), bsdf.eval(b, a, mode));
                assert!(
                    rel_close3(fab, fba, 1e-3),
                    "{name}: f(a,b) {fab} != f(b,a) {fba}"
                );
            }
        }
    }
}

#[test]
fn transmission_is_adjoint() {
    // f_importance(wo, wi) = f_radiance(wi, wo) (Veach 1997 eq. 5.10 with the 1/eta^2 factor).
    let mut r = rng(2);
    for (name, bsdf) in glossy_bsdfs() {
        let mut checked = 0;
        for _ in 0..4000 {
            let (wo, wi) = (random_dir(&mut r), random_dir(&mut r));
            if near_critical(&bsdf, wo, wi) {
                continue;
            }
            let imp = bsdf.eval(wo, wi, TransportMode::Importance);
            let rad = bsdf.eval(wi, wo, TransportMode::Radiance);
            assert!(
                rel_close3(imp, rad, 2e-3),
                "{name}: {imp} vs {rad} at {wo:?} {wi:?}"
            );
            checked += usize::from(wo.z * wi.z < 0.0 && imp.x > 0.0);
        }
        if bsdf.has_transmission() {
            assert!(checked > 100, "{name}: only {checked} transmission pairs");
        }
    }
}

/// True for transmission pairs whose microfacet sees `wo` or `wi` at grazing incidence: there
/// one side is at the critical angle, where `cos theta_t = sqrt(1 - sin^2 theta_t)` loses most
/// of its f32 digits and the two argument orders of the Fresnel term disagree by percents.
fn near_critical(bsdf: &Bsdf, wo: Vec3A, wi: Vec3A) -> bool {
    let eta = bsdf_eta(bsdf);
    if wo.z * wi.z >= 0.0 || eta == 1.0 {
        return false;
    }
    let etap = if wo.z > 0.0 { eta } else { 1.0 / eta };
    let wm = (wi * etap + wo).normalize_or_zero();
    wo.dot(wm).abs().min(wi.dot(wm).abs()) < 0.02
}

#[test]
fn sample_matches_eval_and_pdf() {
    let mut r = rng(3);
    for (name, bsdf) in glossy_bsdfs() {
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            let mut produced = 0;
            for _ in 0..5000 {
                let wo = random_dir(&mut r);
                let u2 = Vec2::new(r.random(), r.random());
                let Some(s) = bsdf.sample(wo, r.random(), u2, mode) else {
                    continue;
                };
                produced += 1;
                assert!(!s.is_specular);
                assert!(
                    (s.wi.length() - 1.0).abs() < 1e-4,
                    "{name}: |wi| = {}",
                    s.wi.length()
                );
                assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{name}: pdf {}", s.pdf);
                let pdf = bsdf.pdf(wo, s.wi, mode);
                let f = bsdf.eval(wo, s.wi, mode);
                // Loose tolerance: the pdf of a sharp lobe is sensitive to the f32 rounding of
                // the recomputed half vector.
                assert!(
                    rel_close(s.pdf, pdf, 2e-2),
                    "{name}: pdf {} vs {pdf}",
                    s.pdf
                );
                assert!(rel_close3(s.f, f, 2e-2), "{name}: f {} vs {f}", s.f);
                let eta = bsdf_eta(&bsdf);
                let expected_eta = match (wo.z * s.wi.z < 0.0, wo.z > 0.0) {
                    (false, _) => 1.0,
                    (true, true) => eta,
                    (true, false) => 1.0 / eta,
                };
                assert!(
                    rel_close(s.eta, expected_eta, 1e-6),
                    "{name}: eta {}",
                    s.eta
                );
            }
            assert!(produced > 3000, "{name}: only {produced} samples");
        }
    }
}

fn bsdf_eta(bsdf: &Bsdf) -> f32 {
    match bsdf {
        Bsdf::RoughDielectric(d) => d.eta(),
        Bsdf::SmoothDielectric(d) => d.eta(),
        _ => 1.0,
    }
}

#[test]
fn positive_eval_implies_positive_pdf() {
    let mut r = rng(4);
    for (name, bsdf) in glossy_bsdfs() {
        for _ in 0..5000 {
            let (wo, wi) = (random_dir(&mut r), random_dir(&mut r));
            let f = bsdf.eval(wo, wi, TransportMode::Radiance);
            assert!(f.is_finite() && f.min_element() >= 0.0, "{name}: f = {f}");
            let pdf = bsdf.pdf(wo, wi, TransportMode::Radiance);
            if f.max_element() > 0.0 {
                assert!(pdf > 0.0, "{name}: f {f} but pdf 0 at {wo:?} {wi:?}");
            }
        }
    }
}

#[test]
fn delta_lobes() {
    let wo = Vec3A::new(0.48, 0.0, 0.6).normalize();
    let mirror = Vec3A::new(-wo.x, -wo.y, wo.z);

    let m = Bsdf::smooth_conductor(Vec3::new(0.9, 0.5, 0.1));
    assert!(m.is_specular() && !m.has_transmission() && m.roughness() == 0.0);
    let s = m.sample(wo, 0.3, Vec2::new(0.1, 0.2), TransportMode::Radiance);
    let s = s.expect("mirror always reflects");
    assert!((s.wi - mirror).length() < 1e-6 && s.is_specular && s.pdf == 1.0 && s.eta == 1.0);
    let w = s.weight();
    assert!(rel_close3(
        w,
        fresnel_schlick(Vec3::new(0.9, 0.5, 0.1), wo.z),
        1e-5
    ));
    assert_eq!(m.eval(wo, mirror, TransportMode::Radiance), Vec3::ZERO);
    assert_eq!(m.pdf(wo, mirror, TransportMode::Radiance), 0.0);

    let g = Bsdf::smooth_dielectric(1.5, Vec3::ONE);
    assert!(g.is_specular() && g.has_transmission());
    let r = fresnel_dielectric(wo.z, 1.5);
    let refl = g.sample(wo, 0.5 * r, Vec2::ZERO, TransportMode::Radiance);
    let refl = refl.expect("reflection lobe");
    assert!((refl.wi - mirror).length() < 1e-6 && rel_close(refl.pdf, r, 1e-6));
    assert!(rel_close3(refl.weight(), Vec3::ONE, 1e-5));
    let tr = g.sample(wo, 0.5 + 0.5 * r, Vec2::ZERO, TransportMode::Radiance);
    let tr = tr.expect("transmission lobe");
    let (expected, _) = refract(wo, Vec3A::Z, 1.5).expect("no TIR");
    assert!((tr.wi - expected).length() < 1e-6 && rel_close(tr.pdf, 1.0 - r, 1e-6));
    assert_eq!(tr.eta, 1.5);
    assert!(rel_close3(tr.weight(), Vec3::splat(1.0 / 2.25), 1e-5));
    let tr_imp = g.sample(wo, 0.5 + 0.5 * r, Vec2::ZERO, TransportMode::Importance);
    assert!(rel_close3(tr_imp.expect("lobe").weight(), Vec3::ONE, 1e-5));

    // Total internal reflection from inside at a grazing angle: always reflects.
    let inside = Vec3A::new(0.95, 0.0, -0.312_249_9);
    let tir = g.sample(inside, 0.999, Vec2::ZERO, TransportMode::Radiance);
    let tir = tir.expect("TIR reflects");
    assert!(tir.wi.z < 0.0 && tir.pdf == 1.0);
}

/// BDPT keeps a delta lobe's discrete probability as its density in both directions
/// (`bdpt::subpath`, "Specular chains"), which is exact only if choosing the lobe is as
/// likely from `wi` as from `wo`: the mirror's 1, and the dielectric's Fresnel `R` and `T`
/// from either side of the interface (checked from outside and inside, both lobes, at
/// every angle short of grazing). Negative control: the transmission
/// probability evaluated as if `wi` were on the other side (the IOR not inverted) differs.
#[test]
fn delta_lobe_choice_is_reciprocal() {
    let mut rng = rng(71);
    let glass = Bsdf::smooth_dielectric(1.5, Vec3::ONE);
    let mirror = Bsdf::smooth_conductor(Vec3::splat(0.8));
    let mut control_differs = 0;
    let mut transmissions = 0;
    for _ in 0..2000 {
        let wo = random_dir(&mut rng);
        // Within 3 degrees of grazing the f32 refraction loses digits (not the lobe choice).
        if wo.z.abs() < 0.05 {
            continue;
        }
        for bsdf in [glass, mirror] {
            let u: f32 = rng.random();
            let Some(fwd) = bsdf.sample(wo, u, Vec2::ZERO, TransportMode::Radiance) else {
                continue;
            };
            // Back from `wi`: the number that picks the same lobe (reflection below R).
            let back_r = match bsdf {
                Bsdf::SmoothDielectric(d) => fresnel_dielectric(fwd.wi.z, d.eta()),
                _ => 1.0,
            };
            let reflected = fwd.eta == 1.0 && (fwd.wi.z > 0.0) == (wo.z > 0.0);
            let u_back = if reflected {
                0.5 * back_r
            } else {
                0.5 + 0.5 * back_r
            };
            let back = bsdf.sample(fwd.wi, u_back, Vec2::ZERO, TransportMode::Radiance);
            let back = back.expect("the reverse lobe exists");
            assert!(
                (back.wi - wo).length() < 1e-4,
                "{wo} -> {} -> {}",
                fwd.wi,
                back.wi
            );
            assert!(
                rel_close(back.pdf, fwd.pdf, 1e-4),
                "lobe probability {} forward, {} back (wo {wo})",
                fwd.pdf,
                back.pdf
            );
            if !reflected {
                transmissions += 1;
                let wrong = 1.0 - fresnel_dielectric(-fwd.wi.z, 1.5);
                if !rel_close(wrong, fwd.pdf, 1e-3) {
                    control_differs += 1;
                }
            }
        }
    }
    assert!(transmissions > 500, "{transmissions} transmissions");
    assert!(
        control_differs > transmissions / 2,
        "negative control: {control_differs} of {transmissions} differ"
    );
}

#[test]
fn grazing_wo_gives_no_sample() {
    let wo = Vec3A::X;
    for (name, bsdf) in glossy_bsdfs() {
        let s = bsdf.sample(wo, 0.5, Vec2::splat(0.5), TransportMode::Radiance);
        assert!(s.is_none(), "{name}: {s:?}");
    }
}

#[test]
fn lambertian_value_stability() {
    let b = Bsdf::lambertian(Vec3::splat(0.5));
    let wo = Vec3A::new(0.0, 0.6, 0.8);
    let s = b.sample(wo, 0.0, Vec2::new(0.75, 0.5), TransportMode::Radiance);
    let s = s.expect("lambertian samples");
    // u = (0.75, 0.5) -> disk point (0.5, 0) -> wi = (0.5, 0, sqrt(0.75)).
    assert!((s.wi - Vec3A::new(0.5, 0.0, 0.75f32.sqrt())).length() < 1e-6);
    assert!(rel_close(
        s.pdf,
        0.75f32.sqrt() / std::f32::consts::PI,
        1e-6
    ));
    // Two-sided: a wo below the surface samples below.
    let below = b.sample(-wo, 0.0, Vec2::new(0.75, 0.5), TransportMode::Radiance);
    assert!(below.expect("two-sided").wi.z < 0.0);
}

#[test]
fn gltf_mapping() {
    let c = Vec3::new(0.8, 0.7, 0.6);
    assert!(matches!(
        Bsdf::from_gltf_params(c, 0.0, 0.5, 0.0, 1.5),
        Bsdf::Lambertian(l) if l.albedo() == c
    ));
    assert!(matches!(
        Bsdf::from_gltf_params(c, 1.0, 0.5, 0.0, 1.5),
        Bsdf::RoughConductor(m) if m.f0() == c && m.distribution().alpha() == 0.25
    ));
    assert!(matches!(
        Bsdf::from_gltf_params(c, 1.0, 0.0, 0.0, 1.5),
        Bsdf::SmoothConductor(_)
    ));
    assert!(matches!(
        Bsdf::from_gltf_params(c, 0.0, 0.01, 1.0, 1.33),
        Bsdf::SmoothDielectric(d) if d.eta() == 1.33 && d.tint() == c
    ));
    assert!(matches!(
        Bsdf::from_gltf_params(c, 1.0, 0.4, 0.9, 1.5),
        Bsdf::RoughDielectric(d) if rel_close(d.distribution().alpha(), 0.16, 1e-6)
    ));
    // Index-matched rough glass degenerates to the smooth pass-through.
    assert!(matches!(
        Bsdf::from_gltf_params(c, 0.0, 0.5, 1.0, 1.0),
        Bsdf::SmoothDielectric(_)
    ));
    // Garbage in: no panic, values sanitised.
    let b = Bsdf::from_gltf_params(
        Vec3::new(f32::NAN, 2.0, -1.0),
        f32::NAN,
        f32::NAN,
        f32::INFINITY,
        -3.0,
    );
    match b {
        Bsdf::RoughDielectric(d) => {
            assert_eq!(d.tint(), Vec3::new(0.0, 1.0, 0.0));
            assert_eq!(d.eta(), 1.5);
            assert_eq!(d.distribution().alpha(), 1.0);
        }
        other => panic!("expected rough dielectric, got {other:?}"),
    }
    assert_eq!(Bsdf::lambertian(c).roughness(), 1.0);
    assert_eq!(Bsdf::rough_conductor(c, 0.3).roughness(), 0.3);
}

#[test]
fn public_types_are_send_sync() {
    fn check<T: Send + Sync + Copy>() {}
    check::<Bsdf>();
    check::<BsdfSample>();
    check::<TransportMode>();
    check::<Ggx>();
}
