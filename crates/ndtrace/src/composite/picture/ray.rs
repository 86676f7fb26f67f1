//! A picture ray's walk through the view's sheets and its integral between their crossings
//! (first hit, volume, illustrative), and the supersampled pixels of the edges.

use super::*;

/// What a view's rays share.
pub(super) struct Ctx<'a, 'b> {
    pub(super) ex: &'a Exact<'b>,
    pub(super) vs: &'a ViewSheets,
    pub(super) cam: &'a Camera3,
    pub(super) mode: CompositeMode,
    pub(super) o: &'a CompositeOptions,
    pub(super) dark_bg: bool,
    pub(super) cut: Option<Cutaway>,
}

impl Ctx<'_, '_> {
    /// The mean of k × k rays within pixel (px, py). Rays that cross the same structure and
    /// enter by the same face ([`Ctx::walk`]'s key) share one integral, the first one's (the
    /// colour between sheets is smooth; the coverage is what varies within a pixel).
    pub(super) fn supersample(
        &self,
        px: usize,
        py: usize,
        k: usize,
        scratch: &mut Scratch,
    ) -> Sample {
        let mut groups: Vec<(u32, Sample, u32)> = Vec::with_capacity(4);
        let mut cands = std::mem::take(&mut scratch.cands);
        self.vs.candidates(px, py, &mut cands);
        for (dx, dy) in pattern(px, py, k) {
            let walked = self.walk(px as f64 + dx, py as f64 + dy, Some(&cands), scratch);
            let (key, walked) = match walked {
                None => (0, None),
                Some((o, d, sig, key)) => (key, Some((o, d, sig))),
            };
            if let Some(g) = groups.iter_mut().find(|g| g.0 == key) {
                g.2 += 1;
                continue;
            }
            let s = match walked {
                None => Sample::EMPTY,
                Some((o, d, sig)) => self.integrate(o, d, sig, scratch),
            };
            groups.push((key, s, 1));
        }
        scratch.cands = cands;
        let mut acc = [0f32; 4];
        let mut half = f32::INFINITY;
        let mut sig = 0u32;
        let mut cover = 0f32;
        for (_, s, count) in &groups {
            for c in 0..4 {
                acc[c] += s.rgba[c] * *count as f32;
            }
            cover += s.cover * *count as f32;
            half = half.min(s.half);
            sig = sig.wrapping_add(s.sig);
        }
        let kk = (k * k) as f32;
        Sample {
            rgba: acc.map(|v| v / kk),
            half,
            sig,
            cover: cover / kk,
        }
    }

    /// The ray through picture point (x, y).
    pub(super) fn sample(&self, x: f64, y: f64, scratch: &mut Scratch) -> Sample {
        match self.walk(x, y, None, scratch) {
            None => Sample::EMPTY,
            Some((org, dir, sig, _)) => self.integrate(org, dir, sig, scratch),
        }
    }

    /// The events of the ray through picture point (x, y), in order, into `scratch`: where it
    /// enters and leaves the covered region, the sheets the 4D eye sees that it crosses (the
    /// illustrative mode), the surfaces; its origin, direction and a summary of what it crosses
    /// (rays with the same summary cross the same kinds of structure in the same order).
    /// `None` when the ray misses the retina's box.
    fn walk(
        &self,
        x: f64,
        y: f64,
        cands: Option<&[u32]>,
        scratch: &mut Scratch,
    ) -> Option<(DVec3, DVec3, u32, u32)> {
        let ex = self.ex;
        let (org, dir, fwd_only) = self.cam.ray_at(x, y);
        let (tb0, tb1) = clip_box(org, dir, ex.n, fwd_only)?;
        // The part of the ray inside the cutaway, removed from the covered region.
        let cut = self.cut.as_ref().and_then(|c| {
            let (a, b) = (org + dir * tb0, org + dir * tb1);
            c.inside(world_of(ex.n, a), world_of(ex.n, b))
                .map(|(s0, s1)| (tb0 + (tb1 - tb0) * s0, tb0 + (tb1 - tb0) * s1))
        });
        scratch.cross.clear();
        match cands {
            Some(c) => self.vs.crossings_of(c, x, y, org, dir, &mut scratch.cross),
            None => self.vs.crossings(x, y, org, dir, &mut scratch.cross),
        }
        let cross = &mut scratch.cross;
        cross.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.sheet.cmp(&b.sheet)));
        // 1. The covered intervals and the events of the ray, in order.
        let events = &mut scratch.events;
        events.clear();
        let inside_cut = |t: f64| cut.is_some_and(|(a, b)| t > a && t < b);
        let push_region = |events: &mut Vec<(f64, u8, Event)>, a: f64, b: f64, at: u32| {
            // [a, b] ∩ box, minus the cut.
            let at = if a >= tb0 { at } else { u32::MAX };
            let (a, b) = (a.max(tb0), b.min(tb1));
            if !(b > a) {
                return;
            }
            let mut parts = [(a, b, at), (0.0, -1.0, at)];
            if let Some((c0, c1)) = cut {
                parts = [(a, b.min(c0), at), (a.max(c1), b, u32::MAX)];
            }
            for (p0, p1, at) in parts {
                if p1 > p0 {
                    events.push((p0, 0, Event::Region(p0, true, at)));
                    events.push((p1, 0, Event::Region(p1, false, u32::MAX)));
                }
            }
        };
        let mut sig: u32 = 0;
        if ex.s.counted {
            let mut count = 0i32;
            let (mut start, mut start_at) = (f64::NEG_INFINITY, u32::MAX);
            for (i, c) in cross.iter().enumerate() {
                let sh = &ex.s.sheets[c.sheet as usize];
                match sh.kind {
                    SheetKind::Mesh { crease, .. } => {
                        let before = count;
                        count += c.enter as i32;
                        if before <= 0 && count > 0 {
                            (start, start_at) = (c.t, i as u32);
                        } else if before > 0 && count <= 0 {
                            push_region(events, start, c.t, start_at);
                        }
                        let internal = before > 0 && count > 0;
                        if (crease || (c.enter != 0 && internal))
                            && c.t > tb0
                            && c.t < tb1
                            && !inside_cut(c.t)
                            && (before > 0 || count > 0)
                        {
                            events.push((c.t, 1, Event::Sheet(i)));
                        }
                    }
                    SheetKind::Surface { .. } => {
                        if c.t > tb0 && c.t < tb1 && !inside_cut(c.t) {
                            events.push((c.t, 2, Event::Surface(i)));
                        }
                    }
                }
            }
            if count > 0 {
                push_region(events, start, f64::INFINITY, start_at);
            }
        } else {
            // Between the count sheets' crossings, one 4D ray says whether it is covered.
            let mut bounds: Vec<f64> = vec![tb0];
            for c in cross.iter() {
                if c.enter != 0 && c.t > tb0 && c.t < tb1 {
                    bounds.push(c.t);
                }
            }
            bounds.push(tb1);
            let mut states = Vec::with_capacity(bounds.len());
            for wdw in bounds.windows(2) {
                let mid = org + dir * (0.5 * (wdw[0] + wdw[1]));
                states.push(wdw[1] > wdw[0] && ex.probe.covered(mid.to_array()));
            }
            let mut j = 0;
            while j < states.len() {
                if states[j] {
                    let a = bounds[j];
                    while j < states.len() && states[j] {
                        j += 1;
                    }
                    push_region(events, a, bounds[j], u32::MAX);
                } else {
                    j += 1;
                }
            }
            // Sheets: creases anywhere covered; count sheets between two covered intervals.
            let covered_at = |t: f64| -> bool {
                match bounds.windows(2).position(|w| t >= w[0] && t < w[1]) {
                    Some(k) => states[k],
                    None => false,
                }
            };
            for (i, c) in cross.iter().enumerate() {
                if !(c.t > tb0 && c.t < tb1) || inside_cut(c.t) {
                    continue;
                }
                match ex.s.sheets[c.sheet as usize].kind {
                    SheetKind::Mesh { crease, .. } => {
                        let eps = 1e-7 * (tb1 - tb0);
                        let (b, a) = (covered_at(c.t - eps), covered_at(c.t + eps));
                        if (crease && (a || b)) || (c.enter != 0 && a && b) {
                            events.push((c.t, 1, Event::Sheet(i)));
                        }
                    }
                    SheetKind::Surface { .. } => events.push((c.t, 2, Event::Surface(i))),
                }
            }
        }
        events.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        // 2. The sheets the 4D eye sees (illustrative), and the summary.
        let illustrative = self.mode == CompositeMode::Illustrative;
        events.retain(|&(_, _, e)| match e {
            Event::Sheet(i) => {
                let c = &cross[i];
                // A fold inside the covered region is an occlusion contour where what it
                // hides lies well behind it (not a small fold of the mesh).
                let obj = ex.s.sheets[c.sheet as usize].object as usize;
                illustrative
                    && !ex.s.looks.get(obj).is_some_and(|l| l.smooth)
                    && ex.sheet_visible(c)
                    && (c.enter == 0 || ex.occludes(c, dir * -(c.enter.signum() as f64)))
            }
            _ => true,
        });
        // What lies behind an opaque layer does not count.
        let opaque_at = |e: &Event| match (*e, self.mode) {
            (Event::Region(_, true, _), CompositeMode::FirstHit) => true,
            (Event::Region(_, true, _), CompositeMode::Volume) => self.o.opacity >= 1.0,
            (Event::Surface(i), CompositeMode::FirstHit | CompositeMode::Volume) => {
                let obj = ex.s.sheets[cross[i].sheet as usize].object;
                ex.s.looks
                    .get(obj as usize)
                    .is_some_and(|l| l.opacity >= 1.0)
            }
            _ => false,
        };
        for (_, _, e) in events.iter() {
            let e = *e;
            let k = match e {
                Event::Region(_, true, _) => 3,
                Event::Region(_, false, _) => 0,
                Event::Sheet(i) => {
                    // Sheets of one flat face share a normal: a face's border is an edge.
                    let sh = &ex.s.sheets[cross[i].sheet as usize];
                    let q = sh.v.map(|v| DVec3::from_array(ex.s.vertices[v as usize].p));
                    let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize_or_zero();
                    let n = if n.x < 0.0 || (n.x == 0.0 && n.y < 0.0) {
                        -n
                    } else {
                        n
                    };
                    let quant = |v: f64| ((v + 1.0) * 64.0) as u32;
                    5 + quant(n.x) * 7919 + quant(n.y) * 104_729 + quant(n.z) * 1_299_709
                }
                Event::Surface(i) => 11 + ex.s.sheets[cross[i].sheet as usize].object,
            };
            sig = sig.wrapping_mul(0x9E37_79B1).wrapping_add(k);
            if opaque_at(&e) {
                break;
            }
        }
        // The key a pixel's rays are grouped by: the summary and the face the ray enters by.
        let entry = events.iter().find_map(|&(_, _, e)| match e {
            Event::Region(_, true, at) if at != u32::MAX => Some(at),
            _ => None,
        });
        let key = match entry {
            Some(i) => {
                let sh = &ex.s.sheets[cross[i as usize].sheet as usize];
                let q = sh.v.map(|v| DVec3::from_array(ex.s.vertices[v as usize].p));
                let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize_or_zero();
                let n = if n.x < 0.0 || (n.x == 0.0 && n.y < 0.0) {
                    -n
                } else {
                    n
                };
                let quant = |v: f64| ((v + 1.0) * 4.0) as u32;
                sig ^ (1 + quant(n.x) + 9 * quant(n.y) + 81 * quant(n.z)).wrapping_mul(0x85EB_CA6B)
            }
            None => sig,
        };
        Some((org, dir, sig, key))
    }

    /// The mode's integral along the ray `org + t·dir` whose events [`Ctx::walk`] put in
    /// `scratch`.
    fn integrate(&self, org: DVec3, dir: DVec3, mut sig: u32, scratch: &Scratch) -> Sample {
        let ex = self.ex;
        let (cross, events) = (&scratch.cross, &scratch.events);
        let fwd = dir.dot(self.cam.forward());
        let mut layers = Layers::new();
        let o = self.o;
        match self.mode {
            CompositeMode::FirstHit => {
                if !(o.opacity > 0.0) {
                    return Sample::EMPTY;
                }
                for &(_, _, e) in events.iter() {
                    match e {
                        Event::Region(t, true, _) => {
                            // Just inside: the 4D ray through the entry point.
                            let next = events
                                .iter()
                                .find_map(|&(_, _, e)| match e {
                                    Event::Region(u, false, _) if u > t => Some(u),
                                    _ => None,
                                })
                                .unwrap_or(t);
                            let eps = (1e-4 * ex.unit).min(0.5 * (next - t));
                            let p = org + dir * (t + eps);
                            let hit = ex.probe.probe(p.to_array());
                            let c = if hit.hit {
                                let (dx, dy) = self.cam.pixel_steps(p);
                                let c = ex.with_lines(&hit, p, dx, dy, texture_line_width(o));
                                ex.cued(c, hit.depth)
                            } else {
                                ex.color_at(p)
                            };
                            sig = sig.wrapping_mul(31).wrapping_add(7 + hit.object as u32)
                                ^ bands(&hit);
                            layers.add(c, 1.0, t);
                            break;
                        }
                        Event::Surface(i) if self.surface(&cross[i], &mut layers, &mut sig) => {
                            break;
                        }
                        _ => {}
                    }
                }
            }
            CompositeMode::Volume | CompositeMode::Illustrative => {
                let illustrative = self.mode == CompositeMode::Illustrative;
                let mut inside_from: Option<f64> = None;
                for &(t, _, e) in events.iter() {
                    match e {
                        Event::Region(_, true, _) => inside_from = Some(t),
                        Event::Region(_, false, _) => {
                            if let Some(a) = inside_from.take() {
                                self.march(org, dir, a, t, illustrative, &mut layers);
                            }
                        }
                        Event::Sheet(i) => {
                            if !illustrative {
                                continue;
                            }
                            if let Some(a) = inside_from {
                                self.march(org, dir, a, t, true, &mut layers);
                                inside_from = Some(t);
                            }
                            let c = &cross[i];
                            let cos = c.cos.max(0.02);
                            let a = (1.0 - (1.0 - SHEET_OPACITY).powf(1.0 / cos)).min(SHEET_MAX);
                            let col = ink(ex.color_at(c.p), 1.0, self.dark_bg);
                            layers.add(col, a, t);
                        }
                        Event::Surface(i) => {
                            if let Some(a) = inside_from {
                                self.march(org, dir, a, t, illustrative, &mut layers);
                                inside_from = Some(t);
                            }
                            self.surface(&cross[i], &mut layers, &mut sig);
                        }
                    }
                    if layers.done() {
                        break;
                    }
                }
            }
            _ => {}
        }
        Sample {
            rgba: layers.rgba(),
            half: (layers.half * fwd) as f32,
            sig,
            cover: if layers.trans < 1.0 { 1.0 } else { 0.0 },
        }
    }

    /// A surface sheet's crossing as a layer (when the 4D eye sees it); whether the ray is
    /// done.
    fn surface(&self, c: &Crossing, layers: &mut Layers, sig: &mut u32) -> bool {
        let ex = self.ex;
        let sh = &ex.s.sheets[c.sheet as usize];
        let SheetKind::Surface { triangle } = sh.kind else {
            return false;
        };
        if let Some((col, d)) = ex.probe.surface(sh.object, triangle, c.b) {
            let a =
                ex.s.looks
                    .get(sh.object as usize)
                    .map_or(1.0, |l| l.opacity);
            *sig = sig.wrapping_mul(31).wrapping_add(11 + sh.object);
            layers.add(ex.cued(col, d), a, c.t);
        }
        layers.done()
    }

    /// Emission–absorption over the covered stretch [a, b] of the ray: opacity per unit
    /// length `opacity` (volume) or the object's interior opacity (illustrative), the colour
    /// interpolated from the cells, at the middles of ⌈(b − a)/step⌉ equal steps.
    fn march(&self, o: DVec3, d: DVec3, a: f64, b: f64, illustrative: bool, layers: &mut Layers) {
        let ex = self.ex;
        let len = b - a;
        if !(len > 0.0) {
            return;
        }
        let steps = ((len / self.o.step).ceil() as usize).max(1);
        let dt = len / steps as f64;
        let per_unit = |alpha: f64| 1.0 - (1.0 - alpha.min(1.0)).powf(dt / ex.unit);
        let plain = per_unit(self.o.opacity);
        let faceted = per_unit(INTERIOR_OPACITY * self.o.opacity);
        let smooth = per_unit(SMOOTH_OPACITY * self.o.opacity);
        for j in 0..steps {
            let t = a + (j as f64 + 0.5) * dt;
            let p = o + d * t;
            let alpha = if illustrative {
                match ex.look_at(p) {
                    Some(l) if l.smooth => smooth,
                    _ => faceted,
                }
            } else {
                plain
            };
            layers.add(ex.color_at(p), alpha, t);
            if layers.done() {
                return;
            }
        }
    }
}
