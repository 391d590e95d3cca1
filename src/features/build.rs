//! [`FeatureSet::build_sized`] in its numbered steps (the module doc's 0-5),
//! one method each on the [`Build`] that carries the counts, timings and
//! isolated points from step to step. A step that finds the deadline passed
//! returns `None`, and the build ends [`Build::incomplete`].

use super::*;

/// One build of a feature set: its inputs, and what the steps counted, timed
/// and kept as isolated points so far.
pub(super) struct Build<'a> {
    drawing: &'a Drawing,
    params: &'a Resolved,
    deadline: &'a Deadline,
    counts: FeatureCounts,
    timing: FeatureTiming,
    points: Vec<FeaturePoint>,
}

/// Steps 0-1's product: each curve (with the index of its first input piece)
/// classified, and by curve its class as drawn where snapping moved it.
pub(super) struct Classified {
    curves: Vec<(u32, classify::Class)>,
    drawn: Vec<Option<classify::Class>>,
}

/// Step 2's product: the pieces after the splits and the coincident
/// outlines, each piece's intervals flat, the trimmer, and the crossings.
pub(super) struct Split {
    pieces: Vec<coincide::Piece>,
    as_drawn: Vec<Option<Parent>>,
    shared: Vec<Option<u32>>,
    /// Lists of sharers ([`FeatureSet::sharers`]).
    pub(super) sharers: Vec<Vec<crate::svg::ShapeId>>,
    flat: Vec<(usize, crossings::Piece)>,
    trimmer: Option<trim::Trimmer>,
    found: crossings::Crossings,
}

/// Step 4's product: the sections and which are primary, which were cut
/// again as secondary runs, and the section each was judged as.
pub(super) struct Separated {
    sections: Vec<Section>,
    primary: Vec<bool>,
    recut: Vec<bool>,
    judged: Vec<u32>,
}

impl<'a> Build<'a> {
    /// A build of `drawing`'s features with `params`, giving up past `deadline`.
    pub(super) fn new(drawing: &'a Drawing, params: &'a Resolved, deadline: &'a Deadline) -> Self {
        Build {
            drawing,
            params,
            deadline,
            counts: FeatureCounts::default(),
            timing: FeatureTiming::default(),
            points: Vec::new(),
        }
    }

    /// What a build stopped by its deadline returns ([`FeatureSet::incomplete`]).
    pub(super) fn incomplete(self) -> FeatureSet {
        FeatureSet::incomplete(self.params, self.points, self.counts, self.timing)
    }

    /// Steps 0 (`continuation`, `snap`) and 1 (`classify`): degenerate curves
    /// become points, straight ones segments.
    pub(super) fn classify(&mut self) -> Classified {
        let (drawing, params) = (self.drawing, self.params);
        let (counts, timing, points) = (&mut self.counts, &mut self.timing, &mut self.points);
        // 0. Pieces of one curve join; ends closer than l_m meet.
        let t = Instant::now();
        let joined = continuation::join(&drawing.features, JOIN_TOL_REL * params.d, params.l_min);
        counts.joined_pieces = joined.joints;
        let pieces: Vec<crate::svg::Feature> = joined.features.iter().map(|(_, f)| *f).collect();
        let snapped = snap::snap(&pieces, params.l_min);
        counts.snapped_ends = snapped.moved;
        counts.snap_collapsed = snapped.collapsed;

        // 1. Classification.
        let mut curves: Vec<(u32, classify::Class)> = Vec::with_capacity(drawing.features.len());
        for f in &drawing.features {
            match f.geom {
                FeatureGeom::Point(_) => counts.input_points += 1,
                FeatureGeom::Line(_) => counts.input_lines += 1,
                FeatureGeom::Cubic(_) => counts.input_cubics += 1,
                FeatureGeom::Conic(_) => counts.input_conics += 1,
            }
        }
        // Each curve's geometry as drawn (before snapping), classified alike: what
        // trimming judges, since the paint tests are built on the drawn outlines.
        let mut drawn: Vec<Option<classify::Class>> = Vec::with_capacity(drawing.features.len());
        for (j, f) in snapped.features {
            // Back to the index of the (first) input piece.
            let i = joined.features[j as usize].0;
            let class = classify::classify(&f.geom, params.eps_m);
            match &class {
                classify::Class::Point(p) => {
                    if !matches!(f.geom, FeatureGeom::Point(_)) {
                        counts.degenerate += 1;
                    }
                    points.push(FeaturePoint {
                        pos: *p,
                        source: f.source,
                    });
                    continue;
                }
                classify::Class::Lines(_)
                    if matches!(f.geom, FeatureGeom::Cubic(_) | FeatureGeom::Conic(_)) =>
                {
                    counts.straight += 1;
                }
                _ => {}
            }
            let unsnapped = pieces[j as usize];
            drawn.push(
                (unsnapped.geom != f.geom)
                    .then(|| classify::classify(&unsnapped.geom, params.eps_m)),
            );
            curves.push((i, class));
        }
        timing.classify_ms = ms(t);
        Classified { curves, drawn }
    }

    /// Step 2: splits (`split`), coincident outlines (`coincide`), crossings
    /// (`crossings`). `None` past the deadline.
    pub(super) fn split(&mut self, classified: Classified) -> Option<Split> {
        let t = Instant::now();
        let (pieces, as_drawn) = self.split_curves(classified);
        let (drawing, params, deadline) = (self.drawing, self.params, self.deadline);
        let (counts, timing) = (&mut self.counts, &mut self.timing);
        // 2a. Coincident outlines: collinear overlaps split, equal pieces once.
        let coincident = coincide::merge(
            pieces,
            as_drawn,
            &drawing.features,
            params.eps_m,
            params.l_min,
            deadline,
        );
        counts.coincident_splits = coincident.splits;
        counts.coincident_merged = coincident.merged;
        let coincide::Merged {
            pieces,
            as_drawn,
            shared,
            sharers,
            ..
        } = coincident;
        if deadline.expired() {
            timing.split_ms = ms(t);
            return None;
        }
        // 2b. Crossings: split both curves where they cross transversally.
        let flat: Vec<(usize, crossings::Piece)> = pieces
            .iter()
            .enumerate()
            .flat_map(|(k, (_, parent, intervals))| {
                intervals
                    .iter()
                    .map(move |&t| (k, crossings::Piece { parent: *parent, t }))
            })
            .collect();
        let trimmer = trim::Trimmer::new(drawing, params.d, params.eps_m);
        let trimmable: Vec<bool> = match &trimmer {
            Some(tr) => flat
                .iter()
                .map(|(k, _)| {
                    tr.trims(drawing.features[pieces[*k].0 as usize].source.shape)
                        && shared[*k]
                            .is_none_or(|g| sharers[g as usize].iter().all(|&s| tr.trims(s)))
                })
                .collect(),
            None => Vec::new(),
        };
        let found = crossings::find(
            &flat.iter().map(|f| f.1).collect::<Vec<_>>(),
            &trimmable,
            params,
            deadline,
        );
        counts.crossing_splits = found.count;
        timing.split_ms = ms(t);
        if deadline.expired() {
            return None;
        }
        Some(Split {
            pieces,
            as_drawn,
            shared,
            sharers,
            flat,
            trimmer,
            found,
        })
    }

    /// Step 2 proper: cubics split at inflections and cusps, then cubics and
    /// conics where they turn too much; straight curves are pieces of one
    /// interval. By piece, its curve as drawn where snapping moved it.
    fn split_curves(
        &mut self,
        classified: Classified,
    ) -> (Vec<coincide::Piece>, Vec<Option<Parent>>) {
        let counts = &mut self.counts;
        let Classified { curves, drawn } = classified;
        // 2. Splits (cubics at inflections and cusps, then cubics and conics where they
        // turn too much).
        let mut pieces: Vec<(u32, Parent, Vec<[f64; 2]>)> = Vec::with_capacity(curves.len());
        // By piece: its curve as drawn, where snapping moved it (see `trim`).
        let mut as_drawn: Vec<Option<Parent>> = Vec::with_capacity(curves.len());
        // Each curve's splits on its own, in parallel; taken in order below.
        let splits: Vec<Option<split::Splits>> = {
            use rayon::prelude::*;
            curves
                .par_iter()
                .map(|(_, class)| match class {
                    classify::Class::Curve(c) => Some(split::split(c)),
                    classify::Class::Conic(c) => Some(split::split_conic(c)),
                    _ => None,
                })
                .collect()
        };
        for (((i, class), drawn), split) in curves.into_iter().zip(drawn).zip(splits) {
            match class {
                classify::Class::Point(_) => {}
                classify::Class::Lines(lines) => {
                    let drawn_lines = match drawn {
                        Some(classify::Class::Lines(d)) if d.len() == lines.len() => Some(d),
                        _ => None,
                    };
                    for (n, l) in lines.into_iter().enumerate() {
                        pieces.push((i, Parent::Line(l), vec![[0.0, 1.0]]));
                        as_drawn.push(drawn_lines.as_ref().map(|d| Parent::Line(d[n])));
                    }
                }
                classify::Class::Curve(c) => {
                    let s = split.expect("internal: a curve's splits");
                    counts.inflection_splits += s.inflection_splits;
                    counts.curvature_splits += s.curvature_splits;
                    pieces.push((i, Parent::Cubic(c), s.intervals));
                    as_drawn.push(match drawn {
                        Some(classify::Class::Curve(d)) => Some(Parent::Cubic(d)),
                        _ => None,
                    });
                }
                classify::Class::Conic(c) => {
                    let s = split.expect("internal: a conic's splits");
                    counts.curvature_splits += s.curvature_splits;
                    pieces.push((i, Parent::Conic(c), s.intervals));
                    as_drawn.push(match drawn {
                        Some(classify::Class::Conic(d)) => Some(Parent::Conic(d)),
                        _ => None,
                    });
                }
            }
        }
        (pieces, as_drawn)
    }

    /// Step 3: trimming and resampling against `size`; the sections, and by
    /// section whether it starts a window between cuts. `None` past the deadline.
    pub(super) fn resample(
        &mut self,
        split: &Split,
        size: &(dyn Fn(Point, FeatureSource, CutFor) -> f64 + Sync),
    ) -> Option<(Vec<Section>, Vec<bool>)> {
        let (drawing, params, deadline) = (self.drawing, self.params, self.deadline);
        let (counts, timing) = (&mut self.counts, &mut self.timing);
        let flat = &split.flat;
        // 3. Trimming (derived outlines only where they bound what is painted) and
        // resampling.
        let t = Instant::now();
        // Each piece on its own, in parallel (the pieces in order, as one
        // after the other; `None` once the deadline passed). The trimming's
        // winding queries can take minutes on a dense dashed path (0182 of the
        // fuzz findings: 85 % of its run).
        let inputs = (drawing, params, deadline);
        let per_piece = |idx: usize| split.resample_piece(idx, inputs, size);
        // A block of pieces at a time, each block's pieces in parallel, so the
        // sections are held twice only for a block (all at once, a drawing of
        // 2 500 tiles peaks some 0.4 GB higher).
        let mut sections = Vec::new();
        let mut window_start = Vec::new();
        for block in (0..flat.len()).step_by(RESAMPLE_BLOCK) {
            let resampled: Vec<Option<Resampled>> = {
                use rayon::prelude::*;
                (block..(block + RESAMPLE_BLOCK).min(flat.len()))
                    .into_par_iter()
                    .with_min_len(RESAMPLE_CHUNK)
                    .map(per_piece)
                    .collect()
            };
            for piece in resampled {
                let (out, trimmed, cover_cuts) = piece?;
                counts.trimmed_pieces += trimmed;
                counts.cover_cuts += cover_cuts;
                for (section, starts) in out {
                    sections.push(section);
                    window_start.push(starts);
                }
            }
        }
        counts.sections = sections.len();
        counts.high_curvature = sections.iter().filter(|s| !s.eligible).count();
        timing.resample_ms = ms(t);
        Some((sections, window_start))
    }

    /// Step 4: μ-separation, secondary runs cut again, primary sections cut
    /// to the size asked (at most `max_sections`). `None` past the deadline.
    pub(super) fn separate(
        &mut self,
        (sections, window_start): (Vec<Section>, Vec<bool>),
        size: &(dyn Fn(Point, FeatureSource, CutFor) -> f64 + Sync),
        max_sections: usize,
    ) -> Option<Separated> {
        let (drawing, params, deadline) = (self.drawing, self.params, self.deadline);
        let (counts, timing, points) = (&mut self.counts, &mut self.timing, &mut self.points);
        // 4. μ-separation.
        let t = Instant::now();
        *points = separation::merge_points(std::mem::take(points), params.mu);
        let mut primary =
            separation::separate(&sections, points, params.mu, params.alpha, deadline);
        if deadline.expired() {
            return None;
        }
        counts.not_separated = sections
            .iter()
            .zip(&primary)
            .filter(|(s, p)| s.eligible && !**p)
            .count();
        let source = |s: &Section| drawing.features[s.feature as usize].source;
        counts.short_isolated =
            separation::demote_short_isolated(&sections, &mut primary, params.mu);
        if let Some(cell) = drawing.cell {
            counts.near_cell_sides = separation::demote_near_sides(
                &sections,
                &mut primary,
                cell,
                params.mu,
                params.alpha,
            );
        }
        // 4b. Runs of secondary sections cut finer than a secondary section
        // needs (a thin stroke's own outline where it is not kept apart) are cut
        // again at their secondary size.
        let (sections, primary, recut) =
            resample::recut_secondary(sections, primary, &window_start, params, &|s, p, cut| {
                size(p, source(s), cut)
            });
        // 4c. Primary sections cut to the size asked where it is below the
        // separation's.
        let resample::Refined {
            sections,
            primary,
            recut,
            judged,
            added,
            unrefined,
        } = resample::refine_primary(
            sections,
            primary,
            recut,
            params,
            &|s, p| size(p, source(s), CutFor::Any),
            max_sections,
        );
        counts.refined_sections = added;
        counts.unrefined_over_budget = unrefined;
        timing.separation_ms = ms(t);
        Some(Separated {
            sections,
            primary,
            recut,
            judged,
        })
    }

    /// Step 5: secondary simplification and assembly of the set.
    pub(super) fn assemble(
        self,
        separated: Separated,
        sharers: Vec<Vec<crate::svg::ShapeId>>,
        start: Instant,
    ) -> FeatureSet {
        let Build {
            drawing,
            params,
            deadline,
            mut counts,
            mut timing,
            mut points,
        } = self;
        let Separated {
            sections,
            mut primary,
            recut,
            judged,
        } = separated;
        // 5. Secondary simplification and assembly.
        let t = Instant::now();
        let simplified = separation::simplify(
            &sections,
            &mut primary,
            drawing,
            &mut points,
            (params.mu, params.alpha),
            &recut,
            deadline,
        );
        counts.collapsed_vertices = simplified.collapsed;
        counts.demoted_after_simplify = simplified.demoted;
        counts.merged_segments = simplified.merged;
        let primary_sections = assemble_primary(&sections, &primary, &judged, drawing);
        counts.primary = primary_sections.len();
        counts.secondary_polylines = simplified.polylines.len();
        counts.secondary_segments = simplified
            .polylines
            .iter()
            .map(|p| p.points.len() - 1)
            .sum();
        counts.points = points.len();
        timing.simplify_ms = ms(t);
        timing.total_ms = ms(start);
        tracing::debug!(?counts, "features");

        FeatureSet {
            params: *params,
            points,
            primary: primary_sections,
            secondary: simplified.polylines,
            sharers,
            counts,
            timing,
        }
    }
}

impl Split {
    /// Step 3 for the flat piece `idx`: its windows between cuts (its ends,
    /// the crossings), each trimmed or resampled against `size`; the sections
    /// with whether each starts its window, and how many windows were
    /// trimmed. `None` once the deadline passed.
    fn resample_piece(
        &self,
        idx: usize,
        (drawing, params, deadline): (&Drawing, &Resolved, &Deadline),
        size: &(dyn Fn(Point, FeatureSource, CutFor) -> f64 + Sync),
    ) -> Option<Resampled> {
        let Split {
            pieces,
            as_drawn,
            shared,
            sharers,
            flat,
            trimmer,
            found,
        } = self;
        if idx % 64 == 0 && deadline.expired() {
            return None;
        }
        let (k, piece) = &flat[idx];
        let (i, parent) = (pieces[*k].0, &pieces[*k].1);
        let mut cuts = vec![piece.t[0]];
        cuts.extend(found.splits[idx].iter().copied());
        cuts.push(piece.t[1]);
        let source = drawing.features[i as usize].source;
        let shape = source.shape;
        // A stroke's straight outline (not shared, not moved by snapping):
        // the parameter ranges opaque shapes painted above it cover, cut
        // where they start and end.
        let covered: Vec<[f64; 2]> = match (trimmer, parent) {
            (Some(tr), Parent::Line(_))
                if shared[*k].is_none() && as_drawn[*k].is_none() && tr.judges_cover(shape) =>
            {
                let (t0, t1) = (piece.t[0], piece.t[1]);
                tr.covered(shape, parent.eval(t0), parent.eval(t1))
                    .into_iter()
                    .map(|[u0, u1]| [t0 + u0 * (t1 - t0), t0 + u1 * (t1 - t0)])
                    .collect()
            }
            _ => Vec::new(),
        };
        let cover_cuts = if covered.is_empty() {
            0
        } else {
            let length = parent.eval(0.0).distance(parent.eval(1.0));
            add_cover_cuts(&mut cuts, &covered, params.eps_m / length)
        };
        // Cut for the separation test no finer than SEPARATION_SIZE_PER_MU μ:
        // primary sections are cut to the size asked after it.
        let floor = SEPARATION_SIZE_PER_MU * params.mu;
        let size = |p: Point| size(p, source, CutFor::Any).max(floor);
        let mut out = Vec::new();
        let mut trimmed = 0;
        for w in cuts.windows(2) {
            let mid = 0.5 * (w[0] + w[1]);
            if covered.iter().any(|r| r[0] <= mid && mid <= r[1]) {
                trimmed += 1;
                continue;
            }
            if let Some(trimmer) = &trimmer
                && !std::iter::once(shape)
                    .chain(
                        shared[*k]
                            .iter()
                            .flat_map(|&g| sharers[g as usize].iter().copied()),
                    )
                    .any(|s| trimmer.keeps(s, parent, as_drawn[*k].as_ref(), w[0], w[1]))
            {
                trimmed += 1;
                continue;
            }
            for (n, p) in resample::resample(parent, w[0], w[1], params, &size)
                .into_iter()
                .enumerate()
            {
                let mut ctrl = p.ctrl;
                // Sections meeting at a crossing share its point exactly.
                if let Some(&x) = found.points.get(&(idx, p.t0.to_bits())) {
                    ctrl.p0 = x;
                }
                if let Some(&x) = found.points.get(&(idx, p.t1.to_bits())) {
                    ctrl.p3 = x;
                }
                let section = Section {
                    feature: i,
                    shared: shared[*k],
                    parent: *parent,
                    t0: p.t0,
                    t1: p.t1,
                    ctrl,
                    eligible: p.eligible,
                };
                out.push((section, n == 0));
            }
        }
        Some((out, trimmed, cover_cuts))
    }
}

/// `cuts` (sorted parameters, the piece's ends first and last) with the ends
/// of the `covered` ranges added: an end within `tol` (in parameter) of a cut
/// is that cut, so a range that ends at a crossing ends at its shared point.
/// Returns how many were added.
fn add_cover_cuts(cuts: &mut Vec<f64>, covered: &[[f64; 2]], tol: f64) -> usize {
    let (first, last) = (cuts[0], cuts[cuts.len() - 1]);
    let near = |cuts: &[f64], t: f64| cuts.iter().any(|&c| (c - t).abs() <= tol);
    let mut added = Vec::new();
    for &t in covered.iter().flatten() {
        if t > first && t < last && !near(cuts, t) && !near(&added, t) {
            added.push(t);
        }
    }
    let n = added.len();
    cuts.extend(added);
    cuts.sort_by(f64::total_cmp);
    n
}
