// The frame's uniforms and the shading every lit primitive shares.
struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    viewport: vec4<f32>,
};
@group(0) @binding(0) var<uniform> frame: Frame;

// Headlight diffuse on both faces, a little ambient and a soft highlight.
fn shade(base: vec3<f32>, n_dot_v: f32) -> vec3<f32> {
    let d = abs(n_dot_v);
    return base * (0.16 + 0.84 * d) + vec3<f32>(0.18 * pow(d, 40.0));
}

// How squarely a surface point faces the eye (1 without a normal).
fn facing(normal: vec3<f32>, world: vec3<f32>) -> f32 {
    if (dot(normal, normal) <= 1e-12) {
        return 1.0;
    }
    return dot(normalize(normal), normalize(frame.eye.xyz - world));
}
