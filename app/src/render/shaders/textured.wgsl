// Meshes with a base-colour texture (glTF materials): vertex colour × base
// colour × texture, lit like every mesh; the image, its sampler and the
// normal map (flat where the material has none) are bound as group 1.
@group(1) @binding(2) var normal_map: texture_2d<f32>;

struct TexturedIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) tangent: vec4<f32>,
    @location(5) alpha_cutoff: f32,
};
struct TexturedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) tangent: vec4<f32>,
    @location(5) alpha_cutoff: f32,
};

@vertex
fn vs_textured(v: TexturedIn) -> TexturedOut {
    var out: TexturedOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.color = v.color;
    out.uv = v.uv;
    out.tangent = v.tangent;
    out.alpha_cutoff = v.alpha_cutoff;
    return out;
}

// The normal map's normal in the interpolated MikkTSpace frame, as glTF
// clients build it (tangent made orthogonal to the normal, bitangent
// w·N×T); the vertex normal where there is no frame.
fn mapped_normal(in: TexturedOut) -> vec3<f32> {
    // Sampled before any branch: implicit derivatives need uniform control flow.
    let m = textureSample(normal_map, atlas_sampler, in.uv).xyz * 2.0 - 1.0;
    let n = in.normal;
    let t = in.tangent.xyz;
    if (in.tangent.w == 0.0 || dot(n, n) <= 1e-12) {
        return n;
    }
    let nn = normalize(n);
    let tt = t - nn * dot(nn, t);
    if (dot(tt, tt) <= 1e-12) {
        return n;
    }
    let tn = normalize(tt);
    let b = cross(nn, tn) * sign(in.tangent.w);
    return tn * m.x + b * m.y + nn * m.z;
}

@fragment
fn fs_textured(in: TexturedOut) -> @location(0) vec4<f32> {
    let c = in.color * textureSample(atlas, atlas_sampler, in.uv);
    let n = mapped_normal(in);
    if (c.a < in.alpha_cutoff) {
        discard;
    }
    return vec4<f32>(shade(c.rgb, facing(n, in.world)), 1.0);
}
