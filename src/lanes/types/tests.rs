//! Tests of the lane types: every operation against the scalar one, lane movement.

use super::*;
use crate::lanes::{Level, at_level};
use crate::rng::SplitMix64;

/// Values that break careless lane code: signed zeros, subnormals, the ends of the range,
/// infinities and NaN, among ordinary numbers.
fn hard_values(rng: &mut SplitMix64) -> [f32; LANES] {
    const HARD: [f32; 8] = [0.0, -0.0, 1e-40, -f32::MAX, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1.0];
    std::array::from_fn(|_| if rng.below(3) == 0 { HARD[rng.below(8)] } else { rng.range(-4.0, 4.0) })
}

/// The bits of each lane, NaN as one value: x86 keeps the sign and payload of whichever
/// operand's NaN it meets first, and vector code may order the operands the other way.
fn bits(v: [f32; LANES]) -> [u32; LANES] {
    v.map(|x| if x.is_nan() { f32::NAN.to_bits() } else { x.to_bits() })
}

/// Every operation gives the scalar operation's bits in every lane, at every level the CPU has
/// (each compiles to different instructions): signed zeros, infinities and subnormals included,
/// NaN where the scalar gives NaN.
#[test]
fn every_operation_gives_the_scalar_bits_at_every_level() {
    let mut rng = SplitMix64::new(3);
    for _ in 0..200 {
        let (a, b, c) = (hard_values(&mut rng), hard_values(&mut rng), hard_values(&mut rng));
        let run = || {
            let (x, y, z) = (F32x16(a), F32x16(b), F32x16(c));
            let (u, v) = (Vec3x16 { x, y, z }, Vec3x16 { x: z, y: x, z: y });
            let mask = x.lt(y) | z.is_nan();
            [
                (x + y).0,
                (x - y).0,
                (x * y).0,
                (x / y).0,
                (2.0 * x - y * 0.5 + 1.0).0,
                (-x).0,
                x.sqrt().0,
                x.abs().0,
                x.max(y).0,
                x.min(y).0,
                F32x16::select(mask, x, y).0,
                u.dot(v).0,
                u.cross(v).x.0,
                u.cross(v).y.0,
                u.cross(v).z.0,
                u.length().0,
            ]
        };
        let want = {
            let s = |l: usize| (a[l], b[l], c[l]);
            let lanes = |f: &dyn Fn(f32, f32, f32) -> f32| -> [f32; LANES] {
                std::array::from_fn(|l| {
                    let (x, y, z) = s(l);
                    f(x, y, z)
                })
            };
            let vec = |x: f32, y: f32, z: f32| (Vec3::new(x, y, z), Vec3::new(z, x, y));
            [
                lanes(&|x, y, _| x + y),
                lanes(&|x, y, _| x - y),
                lanes(&|x, y, _| x * y),
                lanes(&|x, y, _| x / y),
                lanes(&|x, y, _| 2.0 * x - y * 0.5 + 1.0),
                lanes(&|x, _, _| -x),
                lanes(&|x, _, _| x.sqrt()),
                lanes(&|x, _, _| x.abs()),
                lanes(&|x, y, _| if x > y { x } else { y }),
                lanes(&|x, y, _| if x < y { x } else { y }),
                lanes(&|x, y, z| if x < y || z.is_nan() { x } else { y }),
                lanes(&|x, y, z| vec(x, y, z).0.dot(vec(x, y, z).1)),
                lanes(&|x, y, z| vec(x, y, z).0.cross(vec(x, y, z).1).x),
                lanes(&|x, y, z| vec(x, y, z).0.cross(vec(x, y, z).1).y),
                lanes(&|x, y, z| vec(x, y, z).0.cross(vec(x, y, z).1).z),
                lanes(&|x, y, z| vec(x, y, z).0.length()),
            ]
        };
        for &level in Level::ALL {
            let Some(got) = at_level(level, run) else { continue };
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                assert_eq!(bits(*g), bits(*w), "operation {i} at {level:?}: {a:?} {b:?} {c:?}");
            }
        }
    }
}

#[test]
fn masks_gathers_and_columns_move_the_right_lanes() {
    let x = F32x16(std::array::from_fn(|l| l as f32));
    let odd = Mask16::from_bools(std::array::from_fn(|l| l % 2 == 1));
    assert_eq!(odd.to_bools(), std::array::from_fn(|l| l % 2 == 1));
    assert!(odd.any() && !odd.all() && (odd | !odd).all() && !(odd & !odd).any());
    assert!(Mask16::splat(true).all() && !Mask16::splat(false).any());
    assert_eq!(odd.bits(), 0xaaaa);
    assert_eq!(Mask16::from_bits(0x8001).to_bools(), std::array::from_fn(|l| l == 0 || l == 15));
    assert_eq!(Mask16::from_bits(0x1234).bits(), 0x1234);
    assert_eq!(x.gt(F32x16::splat(7.5)), Mask16::from_bools(std::array::from_fn(|l| l > 7)));
    assert_eq!(x.is_finite(), Mask16::splat(true));
    assert_eq!(F32x16::splat(f32::NAN).is_nan(), Mask16::splat(true));
    assert_eq!(x.sum(), (0..LANES).sum::<usize>() as f32);

    let column: Vec<f32> = (0..40).map(|i| i as f32 * 10.0).collect();
    let index = U32x16(std::array::from_fn(|l| (39 - 2 * l) as u32));
    assert_eq!(F32x16::gather(&column, index).0, std::array::from_fn(|l| column[39 - 2 * l]));
    assert_eq!(F32x16::load(&column, 3).0, std::array::from_fn(|l| column[3 + l]));
    let mut out = vec![0.0; 20];
    x.store(&mut out, 2);
    assert_eq!(&out[2..18], &x.0);
    assert_eq!(
        U32x16::select(odd, U32x16::splat(1), U32x16::lane_indices()).0,
        std::array::from_fn(|l| { if l % 2 == 1 { 1 } else { l as u32 } })
    );
    assert!(U32x16::splat(4).is_uniform() && !U32x16::lane_indices().is_uniform());

    let vecs: Vec<Vec3> = (0..20).map(|i| Vec3::new(i as f32, -(i as f32), 0.5 * i as f32)).collect();
    let v = Vec3x16::load(&vecs, 4);
    for l in 0..LANES {
        assert_eq!(v.lane(l), vecs[4 + l]);
    }
    assert_eq!(Vec3x16::gather(&vecs, U32x16(index.0.map(|i| i % 20))).lane(0), vecs[19]);
    let mut back = [Vec3::ZERO; LANES];
    v.store_vec3s(&mut back);
    assert_eq!(&back[..], &vecs[4..20]);
    // Inside the wide code too (a different shuffle).
    let block: &[Vec3; LANES] = vecs[2..18].try_into().unwrap();
    let (wide, mut back) = (crate::lanes::widest(|| Vec3x16::from_vec3s(block)), [Vec3::NAN; LANES]);
    assert_eq!(wide, Vec3x16::from_vec3s(block));
    assert_eq!((wide.x[5], wide.y[5], wide.z[5]), (7.0, -7.0, 3.5));
    crate::lanes::widest(|| wide.store_vec3s(&mut back));
    assert_eq!(&back, block);
}
