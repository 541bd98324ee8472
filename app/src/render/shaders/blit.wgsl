// Copies the offscreen image 1:1 into egui's pass, encoding to sRGB when
// the target does not do it itself.
@group(0) @binding(0) var image: texture_2d<f32>;

struct BlitOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_blit(@builtin(vertex_index) i: u32) -> BlitOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: BlitOut;
    out.clip = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    out.uv = uv;
    return out;
}

fn fetch(uv: vec2<f32>) -> vec4<f32> {
    let size = textureDimensions(image);
    let texel = min(vec2<u32>(max(uv, vec2<f32>(0.0)) * vec2<f32>(size)), size - vec2<u32>(1u));
    return textureLoad(image, texel, 0);
}

@fragment
fn fs_blit_linear(in: BlitOut) -> @location(0) vec4<f32> {
    return vec4<f32>(fetch(in.uv).rgb, 1.0);
}

@fragment
fn fs_blit_gamma(in: BlitOut) -> @location(0) vec4<f32> {
    let c = fetch(in.uv).rgb;
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return vec4<f32>(select(hi, lo, c <= vec3<f32>(0.0031308)), 1.0);
}
