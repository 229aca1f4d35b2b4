//! Shading a tile through bundles: the camera rays of each block of
//! [`BLOCK`] × [`BLOCK`] pixels answered by one
//! [`accel_core::Accelerator::intersect_bundle`] call, then their shadow rays and their
//! ambient-occlusion rays by one [`accel_core::Accelerator::occluded_bundle`] call each.
//!
//! A block's camera rays, in Z order ([`accel_scenes::camera::z_order`]:
//! runs of eight are 4 × 2 pixels), are coherent packets, which a
//! structure with packet traversal (the grid's, the kD-tree's) walks
//! together; the shadow rays of neighbouring hits converge on the light
//! and stay fairly coherent; the ambient-occlusion rays do not, and a
//! structure answers them one at a time, as it would alone.
//!
//! Every pixel is the one [`Shader::pixel`] shades, bit for bit, and so is
//! its tally and digest: a pixel draws its random numbers from its own
//! generator in the same order (the jitter, then the ambient-occlusion
//! directions, sample by sample), every bundle answer is the single-ray
//! answer ([`accel_core::Accelerator::intersect_bundle`]'s promise), and both paths
//! shade a hit with the same code ([`Shader::surface`], [`Shader::lit`],
//! [`PixelSum`]). Counting traversal work has no bundle query, so a
//! counting shader shades the tile one pixel at a time.

use crate::shade::{CameraSample, Pixel, PixelSum, Shader, Surface};
use crate::tiles::Tile;
use accel_core::{Hit, QueryError, Ray, Real};
use accel_scenes::SplitMix64;

/// Side of the blocks whose camera rays go to the accelerator as one
/// bundle: 8 × 8 = 64 rays, the grid's packet (the grid cuts a bundle
/// into packets of 64 rays in order), and the tiles
/// `render bench` measures bundles by ([`crate::bench::TILE`]).
pub const BLOCK: u32 = 8;

/// A ray the accelerator refused, and the pixel it was traced for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelError {
    /// The pixel's column.
    pub x: u32,
    /// The pixel's row.
    pub y: u32,
    /// Why the ray was refused.
    pub error: QueryError,
}

/// A pixel of the block being shaded.
#[derive(Default)]
struct Slot {
    acc: PixelSum,
    /// The first refusal met in the pixel's own order of rays.
    error: Option<QueryError>,
}

/// A hit camera ray of the sample being shaded: its pixel, surface, digest
/// and where its rays lie in the block's bundles.
struct Lit<T> {
    /// Index of the pixel in the block, row by row.
    slot: usize,
    surface: Surface<T>,
    h: u64,
    /// Its shadow ray's index in the shadow bundle, if it has one.
    shadow: Option<usize>,
    /// The index of its first ambient-occlusion ray in that bundle.
    ao: usize,
}

/// The bundles of one block and sample, kept from block to block so that
/// a tile allocates them once.
struct Bundles<T: Real> {
    /// The pixels (their slots) traced, in the order of the camera rays.
    slots: Vec<usize>,
    rngs: Vec<SplitMix64>,
    seeds: Vec<u64>,
    camera: Vec<Ray<T>>,
    hits: Vec<Result<Option<Hit<T>>, QueryError>>,
    lit: Vec<Lit<T>>,
    shadow: Vec<Ray<T>>,
    shadow_blocked: Vec<Result<bool, QueryError>>,
    ao: Vec<Ray<T>>,
    ao_blocked: Vec<Result<bool, QueryError>>,
}

impl<T: Real> Bundles<T> {
    fn new() -> Self {
        let n = (BLOCK * BLOCK) as usize;
        Self {
            slots: Vec::with_capacity(n),
            rngs: Vec::with_capacity(n),
            seeds: Vec::with_capacity(n),
            camera: Vec::with_capacity(n),
            hits: Vec::with_capacity(n),
            lit: Vec::with_capacity(n),
            shadow: Vec::with_capacity(n),
            shadow_blocked: Vec::with_capacity(n),
            ao: Vec::new(),
            ao_blocked: Vec::new(),
        }
    }

    fn clear(&mut self) {
        self.slots.clear();
        self.rngs.clear();
        self.seeds.clear();
        self.camera.clear();
        self.lit.clear();
        self.shadow.clear();
        self.ao.clear();
    }
}

/// Records a pixel's refusal unless an earlier one is already recorded.
fn refuse(slot: &mut Slot, e: QueryError) {
    slot.error.get_or_insert(e);
}

impl<T: Real> Shader<'_, T> {
    /// Shades the pixels of `tile` for which `wanted(x, y)` holds (the
    /// others are left [`Pixel::default`]), through bundles block by block,
    /// or one pixel at a time ([`Shader::pixel`]) when counting work.
    /// Returns the tile's pixels row by row, each exactly what
    /// [`Shader::pixel`] returns for it.
    ///
    /// # Errors
    /// The refusal [`Shader::pixel`] would meet first, shading the tile's
    /// pixels row by row: that of the first pixel (row by row) with one,
    /// the first in that pixel's order of rays.
    pub fn tile(
        &self,
        tile: Tile,
        wanted: impl Fn(u32, u32) -> bool,
    ) -> Result<Vec<Pixel>, PixelError> {
        if self.count {
            return tile
                .pixels()
                .map(|(x, y)| {
                    if !wanted(x, y) {
                        return Ok(Pixel::default());
                    }
                    self.pixel(x, y).map_err(|error| PixelError { x, y, error })
                })
                .collect();
        }
        // Each block is finished (every sample) before the next begins, so
        // the pixels' running sums live for one block only: a small working
        // set beside the bundles.
        let mut out = vec![Pixel::default(); tile.len()];
        let mut first: Option<PixelError> = None;
        let mut slots: Vec<Slot> = Vec::with_capacity((BLOCK * BLOCK) as usize);
        let mut bundles = Bundles::new();
        let w = tile.width() as usize;
        for block in tile.parts(BLOCK) {
            slots.clear();
            slots.resize_with(block.len(), Slot::default);
            for s in 0..self.spp {
                self.block_sample(block, s, &wanted, &mut slots, &mut bundles);
            }
            for ((x, y), slot) in block.pixels().zip(slots.drain(..)) {
                let at = (y - tile.y0) as usize * w + (x - tile.x0) as usize;
                match slot.error {
                    // The first pixel of the tile, row by row, with a refusal.
                    Some(error) => {
                        let earlier = first.is_none_or(|f| (y, x) < (f.y, f.x));
                        if earlier {
                            first = Some(PixelError { x, y, error });
                        }
                    }
                    None if wanted(x, y) => out[at] = slot.acc.finish(self.spp),
                    None => {}
                }
            }
        }
        match first {
            Some(e) => Err(e),
            None => Ok(out),
        }
    }

    /// Shades sample `s` of the wanted pixels of `block` not yet refused,
    /// adding it to their slots (one per pixel of the block, row by row),
    /// or recording their first refusal.
    fn block_sample(
        &self,
        block: Tile,
        s: u32,
        wanted: &impl Fn(u32, u32) -> bool,
        slots: &mut [Slot],
        b: &mut Bundles<T>,
    ) {
        b.clear();
        // In Z order, so that a structure's packets (runs of the bundle)
        // are compact blocks of pixels.
        let (w, h) = (block.width() as usize, block.height() as usize);
        let z = accel_scenes::camera::z_order(w, h);
        for (slot, (x, y)) in
            z.map(|(x, y)| (y * w + x, (block.x0 + x as u32, block.y0 + y as u32)))
        {
            if !wanted(x, y) || slots[slot].error.is_some() {
                continue;
            }
            let CameraSample { ray, rng, seed } = self.camera_sample(x, y, s);
            b.slots.push(slot);
            b.rngs.push(rng);
            b.seeds.push(seed);
            b.camera.push(ray);
        }
        if b.camera.is_empty() {
            return;
        }
        b.hits.clear();
        b.hits.resize(b.camera.len(), Ok(None));
        self.accel.intersect_bundle(&b.camera, &mut b.hits);

        // The camera rays' answers: the sky, a refusal, or a surface whose
        // secondary rays join the bundles.
        for (i, &slot) in b.slots.iter().enumerate() {
            let ray = &b.camera[i];
            let hit = match b.hits[i] {
                Ok(hit) => hit,
                Err(e) => {
                    refuse(&mut slots[slot], e);
                    continue;
                }
            };
            let acc = &mut slots[slot].acc;
            let h = acc.primary(b.seeds[i], hit.as_ref());
            let Some(hit) = hit else {
                acc.add_sample(self.sky(ray.direction.cast()), h);
                continue;
            };
            let ao = b.ao.len();
            let surface = self.surface(ray, &hit, &mut b.rngs[i], &mut b.ao);
            let shadow = surface.shadow.map(|(shadow, _)| {
                b.shadow.push(shadow);
                b.shadow.len() - 1
            });
            b.lit.push(Lit {
                slot,
                surface,
                h,
                shadow,
                ao,
            });
        }
        b.shadow_blocked.clear();
        b.shadow_blocked.resize(b.shadow.len(), Ok(false));
        if !b.shadow.is_empty() {
            self.accel.occluded_bundle(&b.shadow, &mut b.shadow_blocked);
        }
        b.ao_blocked.clear();
        b.ao_blocked.resize(b.ao.len(), Ok(false));
        if !b.ao.is_empty() {
            self.accel.occluded_bundle(&b.ao, &mut b.ao_blocked);
        }

        // The surfaces' answers, in the order `Shader::pixel` traces them:
        // the shadow ray, then the ambient-occlusion rays.
        for lit in &mut b.lit {
            let slot = &mut slots[lit.slot];
            let blocked = match lit.shadow.map(|j| b.shadow_blocked[j]).transpose() {
                Ok(blocked) => blocked,
                Err(e) => {
                    refuse(slot, e);
                    continue;
                }
            };
            let mut ao_blocked = 0;
            for answer in &b.ao_blocked[lit.ao..lit.ao + self.ao as usize] {
                match answer {
                    Ok(blocked) => ao_blocked += u32::from(*blocked),
                    Err(e) => {
                        refuse(slot, *e);
                        break;
                    }
                }
            }
            if slot.error.is_some() {
                continue;
            }
            let c = self.lit(
                &lit.surface,
                blocked,
                ao_blocked,
                &mut slot.acc.pixel.tally,
                &mut lit.h,
            );
            slot.acc.add_sample(c, lit.h);
        }
    }
}
