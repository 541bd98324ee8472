// Meshes with a base-colour texture (glTF materials): vertex colour × base
// colour × texture, lit like every mesh; the image is bound as group 1.
struct TexturedIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) uv: vec2<f32>,
};
struct TexturedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) uv: vec2<f32>,
};

@vertex
fn vs_textured(v: TexturedIn) -> TexturedOut {
    var out: TexturedOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.color = v.color;
    out.uv = v.uv;
    return out;
}

@fragment
fn fs_textured(in: TexturedOut) -> @location(0) vec4<f32> {
    let c = in.color * textureSample(atlas, atlas_sampler, in.uv);
    return vec4<f32>(shade(c.rgb, facing(in.normal, in.world)), 1.0);
}
