//! The checks that turn a scene file's records into values: each number the
//! format documents as an error outside its range is refused here, located at
//! the key that holds it.

use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;
use toml::Spanned;

use super::*;

impl SceneFile {
    pub(super) fn environment(&self, from: &Sources) -> Result<Option<Environment>> {
        let Some(rec) = &self.environment else { return Ok(None) };
        let r = rec.get_ref();
        if !(r.intensity.is_finite() && r.intensity >= 0.0 && r.rotate.is_finite()) {
            return Err(self.invalid(rec.span(), "environment intensity must be finite and ≥ 0, rotate finite"));
        }
        // PNG and JPEG hold sRGB-encoded colours; EXR linear radiance (the loader knows).
        let map = from.texture(r.map.get_ref(), true, Wrap::default())?;
        Ok(Some(Environment::new(map, r.intensity, r.rotate.to_radians(), r.background)))
    }

    pub(super) fn fog(&self) -> Result<Option<Fog>> {
        let Some(rec) = &self.fog else { return Ok(None) };
        let r = rec.get_ref();
        let bad = |msg: &str| Err(self.invalid(rec.span(), msg.to_string()));
        let finite = |v: Option<f32>| v.is_none_or(|v| v.is_finite() && v >= 0.0);
        if !(finite(r.start)
            && finite(r.end)
            && finite(r.density)
            && r.color.iter().all(|c| c.is_finite() && *c >= 0.0))
        {
            return bad("fog distances, density and colour must be finite and ≥ 0");
        }
        let mode = match (r.mode, r.start, r.end, r.density) {
            (FogModeRec::Linear, start, Some(end), None) if end > start.unwrap_or(0.0) => {
                FogMode::Linear { start: start.unwrap_or(0.0), end }
            }
            (FogModeRec::Linear, ..) => return bad("linear fog needs `end` (> `start`, default 0) and no `density`"),
            (FogModeRec::Exp, None, None, Some(density)) => FogMode::Exp { density },
            (FogModeRec::Exp2, None, None, Some(density)) => FogMode::Exp2 { density },
            _ => return bad("exp and exp2 fog need `density` and no `start`/`end`"),
        };
        Ok(Some(Fog { mode, color: r.color.into() }))
    }

    pub(super) fn ambient_occlusion(&self) -> Result<Option<AmbientOcclusion>> {
        let Some(rec) = &self.ambient_occlusion else { return Ok(None) };
        let r = rec.get_ref();
        if r.radius.is_some_and(|r| !(r.is_finite() && r > 0.0)) {
            return Err(self.invalid(rec.span(), "ambient_occlusion `radius` must be finite and > 0"));
        }
        let max = AmbientOcclusion::MAX_RAYS;
        let rays = match r.rays {
            None => AmbientOcclusion::default().rays,
            Some(n) if (1..=i64::from(max)).contains(&n) => n as u32,
            Some(n) => {
                return Err(self.invalid(rec.span(), format!("ambient_occlusion `rays` must be 1 to {max}, not {n}")))
            }
        };
        let screen_space = r.screen_space.unwrap_or(false);
        Ok(Some(AmbientOcclusion { radius: r.radius, rays, screen_space, ..AmbientOcclusion::default() }))
    }

    pub(super) fn lines(&self) -> Result<Option<FeatureLines>> {
        let Some(rec) = &self.lines else { return Ok(None) };
        let r = rec.get_ref();
        let base = FeatureLines::default();
        let widths = FeatureLines::WIDTHS;
        if r.width.is_some_and(|w| !widths.contains(&w)) {
            let (lo, hi) = (widths.start(), widths.end());
            return Err(self.invalid(rec.span(), format!("lines `width` must be {lo} to {hi} pixels")));
        }
        if r.crease.is_some_and(|c| !(0.0..=180.0).contains(&c)) {
            return Err(self.invalid(rec.span(), "lines `crease` must be 0 to 180 degrees"));
        }
        if r.color.is_some_and(|c| !c.iter().all(|v| v.is_finite() && *v >= 0.0)) {
            return Err(self.invalid(rec.span(), "lines `color` must be finite and >= 0"));
        }
        Ok(Some(FeatureLines {
            width: r.width.unwrap_or(base.width),
            colour: r.color.map_or(base.colour, Vec3::from),
            hidden: r.hidden.unwrap_or(base.hidden),
            crease_deg: r.crease.unwrap_or(base.crease_deg),
        }))
    }

    pub(super) fn antialias(&self) -> Result<Antialias> {
        let Some(rec) = &self.image.antialias else { return Ok(Antialias::default()) };
        let rec = rec.get_ref();
        let method = rec.method.get_ref().as_str();
        if method != "edge" {
            if let Some(key) = [&rec.edges, &rec.filter].into_iter().flatten().next() {
                return Err(self.invalid(key.span(), "`edges` and `filter` belong to method \"edge\""));
            }
        }
        let mut mode = EdgeMode::default();
        if let Some(e) = &rec.edges {
            mode.selection = match e.get_ref().as_str() {
                "outline" => EdgeSelection::Outline,
                "all" => EdgeSelection::All,
                other => {
                    return Err(
                        self.invalid(e.span(), format!("unknown edges '{other}' (expected \"outline\" or \"all\")"))
                    )
                }
            };
        }
        if let Some(f) = &rec.filter {
            mode.filter = match f.get_ref().as_str() {
                "coverage" => EdgeFilter::Coverage,
                "paper" => EdgeFilter::Paper,
                other => {
                    return Err(self
                        .invalid(f.span(), format!("unknown filter '{other}' (expected \"coverage\" or \"paper\")")))
                }
            };
        }
        match (method, &rec.samples) {
            ("none", None) => Ok(Antialias::None),
            ("none", Some(n)) => Err(self.invalid(n.span(), "method \"none\" takes no samples")),
            ("edge", None) => Ok(Antialias::Edge(mode)),
            ("edge", Some(n)) => Err(self.invalid(n.span(), "method \"edge\" takes no samples")),
            ("jitter", None) => Err(self.invalid(rec.method.span(), "method \"jitter\" needs `samples = n`")),
            ("jitter", Some(n)) => match u32::try_from(*n.get_ref()) {
                Ok(k @ 1..=MAX_JITTER_SAMPLES) => Ok(Antialias::Jitter(k)),
                _ => Err(self.invalid(n.span(), format!("samples must be between 1 and {MAX_JITTER_SAMPLES}"))),
            },
            (other, _) => Err(self.invalid(
                rec.method.span(),
                format!("unknown antialiasing method '{other}' (expected \"none\", \"edge\" or \"jitter\")"),
            )),
        }
    }
    pub(super) fn camera(&self, c: &Spanned<CameraRec>) -> Result<Camera> {
        let r = c.get_ref();
        let projection = match r.projection {
            ProjectionRec::Perspective => Projection::Perspective { fov_y_deg: r.fov },
            ProjectionRec::Orthographic => {
                let height = r.height.ok_or_else(|| {
                    self.invalid(c.span(), "an orthographic camera needs `height` (world units shown top to bottom)")
                })?;
                Projection::Orthographic { height }
            }
        };
        let cam = Camera {
            eye: r.eye.into(),
            target: r.target.into(),
            up: r.up.into(),
            near: r.near,
            far: r.far,
            projection,
            shift: glam::Vec2::ZERO,
        };
        cam.validate().map_err(|m| self.invalid(c.span(), m))?;
        Ok(cam)
    }

    /// The background colour: finite and ≥ 0.
    pub(super) fn background(&self) -> Result<Vec3> {
        let b = &self.image.background;
        let ok = b.get_ref().iter().all(|c| c.is_finite() && *c >= 0.0);
        ok.then(|| Vec3::from(*b.get_ref())).ok_or_else(|| self.invalid(b.span(), "background must be finite and ≥ 0"))
    }

    /// The exposure: a finite number of stops, or `auto`.
    pub(super) fn exposure(&self) -> Result<Exposure> {
        let e = &self.image.exposure;
        match e.get_ref() {
            ExposureRec::Stops(ev) if !ev.is_finite() => {
                Err(self.invalid(e.span(), "exposure must be a finite number of stops or \"auto\""))
            }
            rec => Ok((*rec).into()),
        }
    }

    pub(super) fn light(&self, l: &Spanned<LightRec>) -> Result<Light> {
        let r = l.get_ref();
        let need = |v: Option<V3>, key: &str| {
            v.map(Vec3::from)
                .ok_or_else(|| self.invalid(l.span(), format!("a {:?} light needs `{key}`", r.kind).to_lowercase()))
        };
        let aim = |from: Option<V3>| -> Result<Vec3> {
            let d = match (r.direction, r.target, from) {
                (Some(d), _, _) => Vec3::from(d),
                (None, Some(t), Some(p)) => Vec3::from(t) - Vec3::from(p),
                _ => return Err(self.invalid(l.span(), "this light needs `direction` (or `position` and `target`)")),
            };
            d.try_normalize().ok_or_else(|| self.invalid(l.span(), "the light direction has zero length"))
        };
        let kind = match r.kind {
            LightType::Point => LightKind::Point { position: need(r.position, "position")? },
            LightType::Directional => LightKind::Directional { direction: aim(r.position)? },
            LightType::Spot => LightKind::Spot {
                position: need(r.position, "position")?,
                direction: aim(r.position)?,
                inner: r.inner_angle.to_radians(),
                outer: r.outer_angle.to_radians(),
            },
        };
        let places = match kind {
            LightKind::Point { position } => [position, Vec3::ZERO],
            LightKind::Spot { position, direction, .. } => [position, direction],
            LightKind::Directional { direction } => [direction, Vec3::ZERO],
        };
        if !places.iter().all(|p| p.is_finite()) {
            return Err(self.invalid(l.span(), "light position, direction and target must be finite"));
        }
        if r.kind == LightType::Spot
            && !(0.0 <= r.inner_angle && r.inner_angle <= r.outer_angle && r.outer_angle <= 180.0)
        {
            return Err(self.invalid(l.span(), "spot angles must satisfy 0 ≤ inner_angle ≤ outer_angle ≤ 180"));
        }
        let values = [r.intensity, r.ambient, r.size, r.color[0], r.color[1], r.color[2]];
        if values.iter().any(|v| !v.is_finite() || *v < 0.0) {
            let message = "light colour, intensity, ambient and size must be finite numbers ≥ 0 (and below 3.4e38, the largest kage holds)";
            return Err(self.invalid(l.span(), message));
        }
        let falloff = match r.falloff {
            FalloffRec::None => Falloff::None,
            FalloffRec::InverseSquare => Falloff::InverseSquare,
        };
        Ok(Light {
            kind,
            color: r.color.into(),
            intensity: r.intensity,
            ambient: r.ambient,
            size: r.size,
            falloff,
            shadow: self.shadow(r.shadow.as_ref())?,
            only: None, // resolved once the objects exist
        })
    }

    /// A warning, located at the light's `[light.shadow]` table, for each key
    /// it gives that its method does not read ([`ShadowSettings::applies`]).
    pub(super) fn shadow_key_warnings(&self, rec: &Spanned<ShadowRec>, settings: &ShadowSettings) -> Vec<String> {
        let r = rec.get_ref();
        let given = [
            ("resolution", r.resolution.is_some()),
            ("bias", r.bias.is_some()),
            ("slope", r.slope.is_some()),
            ("pcf", r.pcf.is_some()),
            ("samples", r.samples.is_some()),
            ("bits", r.bits.is_some()),
            ("scale", r.scale.is_some()),
            ("antialias", r.antialias.is_some()),
            ("focus", r.focus.is_some()),
            ("search", r.search.is_some()),
            ("falloff", r.falloff.is_some()),
            ("depth_aware", r.depth_aware.is_some()),
            ("half", r.half.is_some()),
            ("hard", r.hard.is_some()),
            ("points", r.points.is_some()),
            ("blockers", r.blockers.is_some()),
            ("filter", r.filter.is_some()),
        ];
        let ignored: Vec<&str> =
            given.iter().filter(|(k, set)| *set && !settings.applies(k)).map(|(k, _)| *k).collect();
        if ignored.is_empty() {
            return Vec::new();
        }
        let origin = self.origin.clone().unwrap_or(Origin { path: "<scene>".into(), text: Arc::from("") });
        let at = SourceLocation::new(origin.path, origin.text, rec.span());
        let method = settings.method.name();
        let read: Vec<&str> = given.iter().map(|(k, _)| *k).filter(|k| settings.applies(k)).collect();
        let list = |keys: &[&str]| keys.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
        vec![format!(
            "{at}: shadow method `{method}` does not read {} (ignored); it reads {}",
            list(&ignored),
            if read.is_empty() { "nothing else".to_string() } else { list(&read) }
        )]
    }

    pub(super) fn shadow(&self, rec: Option<&Spanned<ShadowRec>>) -> Result<ShadowSettings> {
        let mut s = ShadowSettings::default();
        let Some(rec) = rec else { return Ok(s) };
        let r = rec.get_ref();
        if let Some(name) = &r.method {
            let method = ShadowMethod::named(name.get_ref()).ok_or_else(|| {
                let names = ShadowMethod::names().iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ");
                self.invalid(name.span(), format!("unknown shadow method `{}`; kage has {names}", name.get_ref()))
            })?;
            s = s.with_method(method);
        }
        let count = |v: &Option<Spanned<i64>>, lo: i64, hi: i64, what: &str| -> Result<Option<u32>> {
            match v {
                Some(n) if !(lo..=hi).contains(n.get_ref()) => {
                    Err(self.invalid(n.span(), format!("{what} must be between {lo} and {hi}")))
                }
                Some(n) => Ok(Some(*n.get_ref() as u32)),
                None => Ok(None),
            }
        };
        if let Some(n) = count(&r.resolution, 16, 16384, "shadow resolution")? {
            (s.resolution, s.by_need) = (n, false);
        }
        s.pcf = count(&r.pcf, 1, 15, "pcf")?.unwrap_or(s.pcf);
        s.samples = count(&r.samples, 1, 256, "shadow samples")?.unwrap_or(s.samples);
        s.bits = count(&r.bits, 4, 16, "shadow bits")?.unwrap_or(s.bits);
        s.antialias = r.antialias.unwrap_or(s.antialias);
        s.search = count(&r.search, 0, 64, "shadow search")?.unwrap_or(s.search);
        s.blockers = count(&r.blockers, 1, 256, "shadow blockers")?.unwrap_or(s.blockers);
        s.filter = count(&r.filter, 1, 256, "shadow filter")?.unwrap_or(s.filter);
        s.depth_aware = r.depth_aware.unwrap_or(s.depth_aware);
        s.half = r.half.unwrap_or(s.half);
        s.focus = r.focus.map(Vec3::from).or(s.focus);
        if let Some(p) = r.falloff {
            s.penumbra = match p {
                PenumbraRec::Linear => PenumbraFalloff::Linear,
                PenumbraRec::Smooth => PenumbraFalloff::Smooth,
            };
        }
        if let Some(p) = r.points {
            s.points = match p {
                PointsRec::Paper => PenumbraPoints::Paper,
                PointsRec::Matched => PenumbraPoints::Matched,
                PointsRec::Ring => PenumbraPoints::Ring,
            };
        }
        if let Some(h) = r.hard {
            s.hard = match h {
                HardRec::Map => HardShadows::Map,
                HardRec::Slb => HardShadows::Slb,
            };
        }
        if let Some(scale) = &r.scale {
            let v = *scale.get_ref();
            if !(v.is_finite() && v > 0.0) {
                return Err(self.invalid(scale.span(), "shadow scale must be a finite number above 0"));
            }
            s.scale = v;
        }
        for (v, slot) in [(r.bias, &mut s.bias), (r.slope, &mut s.slope)] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(self.invalid(rec.span(), "shadow bias and slope must be finite and ≥ 0"));
                }
                *slot = v;
            }
        }
        Ok(s)
    }

    /// Turns each light's `only = [names]` into object indices: a name means every
    /// object its [[object]] record produced.
    pub(super) fn resolve_only(&self, scene: &mut Scene, produced: &[(Option<String>, Range<usize>)]) -> Result<()> {
        for (light, rec) in scene.lights.iter_mut().zip(&self.lights) {
            let Some(names) = &rec.get_ref().only else { continue };
            let mut objects = Vec::new();
            for name in names {
                let hits: Vec<_> =
                    produced.iter().filter(|(n, _)| n.as_deref() == Some(name.get_ref().as_str())).collect();
                if hits.is_empty() {
                    let msg = format!("no [[object]] named '{}' for this light to light", name.get_ref());
                    return Err(self.invalid(name.span(), msg));
                }
                objects.extend(hits.into_iter().flat_map(|(_, r)| r.clone()));
            }
            light.only = Some(objects);
        }
        Ok(())
    }

    pub(super) fn material(&self, r: &MaterialRec, from: &Sources) -> Result<Material> {
        let wrap = match r.wrap {
            WrapRec::Repeat => Wrap::Repeat,
            WrapRec::Clamp => Wrap::Clamp,
            WrapRec::Mirror => Wrap::Mirror,
        };
        let texture = |maps: &Option<MapsRec>, srgb: bool| -> Result<Vec<Arc<Texture>>> {
            maps.as_ref().map_or(&[][..], MapsRec::paths).iter().map(|p| from.texture(p, srgb, wrap)).collect()
        };
        Ok(Material {
            name: r.name.get_ref().clone(),
            ka: r.ka.unwrap_or(r.kd).into(),
            kd: r.kd.into(),
            ks: r.ks.into(),
            shininess: r.shininess,
            ke: r.ke.into(),
            maps: crate::scene::ComponentMaps {
                ambient: texture(&r.ka_map, true)?,
                diffuse: texture(&r.kd_map, true)?,
                specular: texture(&r.ks_map, true)?,
                emission: texture(&r.ke_map, true)?,
                mirror: None,
                roughness: None,
                alpha: None,
                normal: None,
                filter: match r.filter {
                    FilterRec::Trilinear => Filter::Trilinear,
                    FilterRec::Bilinear => Filter::Bilinear,
                },
            },
            two_sided: r.two_sided,
            kr: r.kr.into(),
            kt: r.kt.into(),
            km: r.km.into(),
            opacity: match &r.opacity {
                Some(a) if !(0.0..=1.0).contains(a.get_ref()) => {
                    return Err(self.invalid(a.span(), "opacity must be between 0 and 1"))
                }
                Some(a) => *a.get_ref(),
                None => 1.0,
            },
            ior: match &r.ior {
                Some(ior) if !(ior.get_ref().is_finite() && *ior.get_ref() >= 1.0) => {
                    return Err(self.invalid(ior.span(), "the index of refraction must be a finite number ≥ 1"))
                }
                Some(ior) => *ior.get_ref(),
                None => 1.5,
            },
            cutoff: None,
        })
    }
}
