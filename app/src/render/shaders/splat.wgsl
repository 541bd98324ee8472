// Textured splats (AMG §4), blended by their partition of unity Ψ.
@group(1) @binding(0) var atlas: texture_2d<f32>;
@group(1) @binding(1) var atlas_sampler: sampler;

struct SplatIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};
struct SplatOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) facing: f32,
};

@vertex
fn vs_splat(v: SplatIn) -> SplatOut {
    var out: SplatOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.uv = v.uv;
    out.facing = dot(v.normal, frame.eye.xyz - v.position);
    return out;
}

// Back-facing primitives are skipped (§4); only the core of a domain
// (Ψ ≥ ½) locks the depth, and clears the background there.
@fragment
fn fs_splat_depth(in: SplatOut) -> @location(0) vec4<f32> {
    let t = textureSample(atlas, atlas_sampler, in.uv);
    if (t.a < 0.5 || in.facing < 0.0) {
        discard;
    }
    return vec4<f32>(0.0, 0.0, 0.0, 1.0);
}

// Colour weighted by Ψ; the weights of overlapping domains sum to one.
@fragment
fn fs_splat(in: SplatOut) -> @location(0) vec4<f32> {
    let t = textureSample(atlas, atlas_sampler, in.uv);
    if (t.a <= 0.0 || in.facing < 0.0) {
        discard;
    }
    return vec4<f32>(t.rgb * t.a, t.a);
}
