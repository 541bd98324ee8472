// Lit meshes (headlight, two-sided; opaque, or translucent voxel layers by
// their alpha), unlit lines, and points as discs.

struct MeshIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};
struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

fn mesh_out(v: MeshIn) -> MeshOut {
    var out: MeshOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.color = v.color;
    return out;
}

@vertex
fn vs_mesh(v: MeshIn) -> MeshOut {
    return mesh_out(v);
}

@fragment
fn fs_mesh(in: MeshOut) -> @location(0) vec4<f32> {
    return vec4<f32>(shade(in.color.rgb, facing(in.normal, in.world)), in.color.a);
}

// Lines (wireframes, outlines, boxes) a hair in front of the surfaces they
// lie on, so they win the depth test against their own triangles.
@vertex
fn vs_line(v: MeshIn) -> MeshOut {
    var out = mesh_out(v);
    out.clip.z = out.clip.z - 2e-4 * out.clip.w;
    return out;
}

@fragment
fn fs_unlit(in: MeshOut) -> @location(0) vec4<f32> {
    return in.color;
}

struct PointIn {
    @location(0) position: vec3<f32>,
    @location(1) radius: f32,
    @location(2) normal: vec3<f32>,
    @location(3) color: vec3<f32>,
};
struct PointOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) corner: vec2<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) to_eye: vec3<f32>,
};

@vertex
fn vs_points(@builtin(vertex_index) i: u32, p: PointIn) -> PointOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let c = corners[i % 6u];
    let clip = frame.view_proj * vec4<f32>(p.position, 1.0);
    var radius_px = frame.viewport.w;
    if (p.radius > 0.0) {
        radius_px = max(p.radius * frame.viewport.z / max(clip.w, 1e-6), 1.0);
    }
    let offset = c * radius_px * 2.0 / frame.viewport.xy;
    var out: PointOut;
    out.clip = vec4<f32>(clip.xy + offset * clip.w, clip.z, clip.w);
    out.corner = c;
    out.normal = p.normal;
    out.color = p.color;
    out.to_eye = frame.eye.xyz - p.position;
    return out;
}

@fragment
fn fs_points(in: PointOut) -> @location(0) vec4<f32> {
    let r2 = dot(in.corner, in.corner);
    if (r2 > 1.0) {
        discard;
    }
    // Without a normal the disc is shaded like a small sphere facing the camera.
    var n_dot_v = sqrt(1.0 - r2);
    if (dot(in.normal, in.normal) > 1e-12 && dot(in.to_eye, in.to_eye) > 0.0) {
        n_dot_v = dot(normalize(in.normal), normalize(in.to_eye));
    }
    return vec4<f32>(shade(in.color, n_dot_v), 1.0);
}
