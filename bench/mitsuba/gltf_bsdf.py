"""glTF 2.0's metallic-roughness BRDF (specification, appendix B) as a Mitsuba 3 Python BSDF, `gltf_brdf`.

    import gltf_bsdf; gltf_bsdf.register(mi)      # after mi.set_variant(...); works in scalar_rgb and llvm_ad_rgb
    {"type": "gltf_brdf", "r": .5, "g": .5, "b": .5, "metallic": 0, "roughness": .5, "f0": 0.04}

f = mix(dielectric, metal, metallic) with
    dielectric = (1 - F) * base / pi + F * D * V,   F = f0 + (1 - f0) (1 - |V.H|)^5   (fresnel_mix, f0 = 0.04 at ior 1.5)
    metal      = (base + (1 - base) (1 - |V.H|)^5) * D * V
D: GGX with alpha = roughness^2; V: height-correlated Smith visibility G / (4 |N.L| |N.V|), the spec's
implementation form. Single scattering, no energy compensation. Constant factors only (no textures); one-sided
(wrap it in `twosided` for doubleSided). Sampling: cosine hemisphere or GGX normals (probability 0.5 each when
there is a specular lobe), pdf of the mixture, so Mitsuba's MIS sees the right densities. Written from the spec,
not from kelvin's code, to check kelvin's glTF BRDF independently.
"""


def register(mi):
    import drjit as dr

    class GltfBrdf(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.base = mi.Color3f(props.get("r", 1.0), props.get("g", 1.0), props.get("b", 1.0))
            self.metallic = float(props.get("metallic", 0.0))
            rough = min(max(float(props.get("roughness", 1.0)), 0.0), 1.0)
            self.alpha = max(rough * rough, 1e-3)
            self.f0 = float(props.get("f0", 0.04))
            self.p_spec = 0.5 if (self.metallic > 0 or self.f0 > 0) else 0.0
            flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            gflags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags, gflags]
            self.m_flags = flags | gflags

        def _d(self, cos_h):
            a2 = self.alpha * self.alpha
            t = cos_h * cos_h * (a2 - 1.0) + 1.0
            return a2 / (dr.pi * t * t)

        def _eval_pdf(self, wi, wo):
            ci, co = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
            ok = (ci > 0) & (co > 0)
            h = dr.normalize(wi + wo)
            vh = dr.clip(dr.dot(wi, h), 0.0, 1.0)
            tail = dr.power(1.0 - vh, 5.0)
            a2 = self.alpha * self.alpha
            vis = 0.5 / dr.maximum(ci * dr.sqrt(co * co * (1 - a2) + a2) + co * dr.sqrt(ci * ci * (1 - a2) + a2), 1e-12)
            dv = self._d(h.z) * vis
            fd = self.f0 + (1.0 - self.f0) * tail if self.f0 > 0 else 0.0
            m = self.metallic
            diffuse = (1.0 - m) * (1.0 - fd) * self.base * dr.inv_pi
            metal = self.base + (1.0 - self.base) * tail
            value = (diffuse + dv * ((1.0 - m) * fd + m * metal)) * co
            pdf = (1.0 - self.p_spec) * co * dr.inv_pi
            if self.p_spec > 0:
                pdf += self.p_spec * self._d(h.z) * h.z / (4.0 * dr.maximum(dr.dot(wo, h), 1e-12))
            return dr.select(ok, value, 0.0), dr.select(ok, pdf, 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            use_spec = sample1 < self.p_spec
            wo_d = mi.warp.square_to_cosine_hemisphere(sample2)
            # GGX normal from its D(h) cos(h) density: tan^2 = a^2 u / (1 - u)
            phi = 2.0 * dr.pi * sample2.y
            t2 = self.alpha * self.alpha * sample2.x / dr.maximum(1.0 - sample2.x, 1e-12)
            cos_t = 1.0 / dr.sqrt(1.0 + t2)
            sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
            h = mi.Vector3f(sin_t * dr.cos(phi), sin_t * dr.sin(phi), cos_t)
            wo_s = 2.0 * dr.dot(wi, h) * h - wi
            wo = dr.select(use_spec, wo_s, wo_d)
            value, pdf = self._eval_pdf(wi, wo)
            bs = mi.BSDFSample3f()
            bs.wo, bs.pdf, bs.eta = wo, pdf, 1.0
            bs.sampled_component = dr.select(use_spec, mi.UInt32(1), mi.UInt32(0))
            bs.sampled_type = dr.select(use_spec, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                        mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
            ok = active & (pdf > 0) & (mi.Frame3f.cos_theta(wi) > 0)
            return bs, dr.select(ok, value / dr.maximum(pdf, 1e-20), 0.0)

        def eval(self, ctx, si, wo, active=True):
            return self._eval_pdf(si.wi, wo)[0]

        def pdf(self, ctx, si, wo, active=True):
            return self._eval_pdf(si.wi, wo)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            return self._eval_pdf(si.wi, wo)

        def to_string(self):
            return f"GltfBrdf[metallic={self.metallic}, alpha={self.alpha}, f0={self.f0}]"

    mi.register_bsdf("gltf_brdf", lambda props: GltfBrdf(props))
