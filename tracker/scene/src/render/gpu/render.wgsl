// EventTrack6D GPU renderer: one pass writes depth, normal, mask and shaded intensity of the nearest surface into a
// single Rgba32Uint target (read back and unpacked on the CPU).
//
// Camera frame: OpenCV (x right, y down, z forward), metres. Pixel (u, v) has its centre at image coordinate (u, v),
// i.e. at framebuffer coordinate (u + 0.5, v + 0.5). The depth buffer holds near / z (1 at the near plane, towards 0
// at infinity: an infinite far plane, nearest = greatest), compared with GREATER like the CPU backend's inverse depth.

struct Frame {
    // fx, fy, cx, cy (pixels).
    intrinsics: vec4<f32>,
    // width, height (pixels), near (metres), unused.
    size: vec4<f32>,
    // Unit direction towards the light (camera frame), ambient term.
    light: vec4<f32>,
    // Diffuse term, shade flag (1: shade intensity, 0: geometry only, intensity 0), unused x2.
    diffuse: vec4<f32>,
}

struct Instance {
    // Rows of the rotation R_cam_obj (w unused).
    row0: vec4<f32>,
    row1: vec4<f32>,
    row2: vec4<f32>,
    // Translation t_cam_obj, metres (w unused).
    translation: vec4<f32>,
    // x: mask label.
    mask: vec4<u32>,
}

struct Material {
    // Constant albedo luminance (used when width == 0).
    albedo: f32,
    // First texel of the luminance texture in `texels`.
    offset: u32,
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> instance: Instance;
@group(1) @binding(0) var<storage, read> materials: array<Material>;
@group(1) @binding(1) var<storage, read> texels: array<f32>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) material: u32,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) view: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) material: u32,
}

fn rotate(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(instance.row0.xyz, v), dot(instance.row1.xyz, v), dot(instance.row2.xyz, v));
}

// The vertex in clip space and the camera frame.
fn transform(v: VertexIn) -> VertexOut {
    let p = rotate(v.position) + instance.translation.xyz;
    let k = frame.intrinsics;
    let w = frame.size.x;
    let h = frame.size.y;
    // Framebuffer x = fx X / Z + cx + 0.5; NDC x = 2 x / W - 1 (y flipped: NDC y is up). Multiplied by w = Z.
    let cx = 2.0 * (k.x * p.x + (k.z + 0.5) * p.z) / w - p.z;
    let cy = p.z - 2.0 * (k.y * p.y + (k.w + 0.5) * p.z) / h;
    var out: VertexOut;
    // Clip z = near, w = Z: NDC depth near / Z, clipped where Z < near.
    out.clip = vec4<f32>(cx, cy, frame.size.z, p.z);
    out.view = p;
    out.normal = rotate(v.normal);
    out.uv = v.uv;
    out.material = v.material;
    return out;
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    return transform(v);
}

// Maps a texture coordinate into [0, 1) (repeat), like the CPU backend's `wrap_unit`.
fn wrap_unit(t: f32) -> f32 {
    if (t != t || abs(t) >= 8388608.0) {
        return 0.0;
    }
    let f = t - trunc(t);
    return select(f, f + 1.0, f < 0.0);
}

// Lower and upper wrapped neighbours of a coordinate in [-0.5, n - 0.5).
fn neighbours(i: f32, n: u32) -> vec2<u32> {
    var lo: u32;
    if (i < 0.0) {
        lo = n - 1u;
    } else {
        lo = min(u32(i), n - 1u);
    }
    let hi = select(lo + 1u, 0u, lo + 1u >= n);
    return vec2<u32>(lo, hi);
}

// Bilinear sample of a luminance texture at OBJ coordinates (v up), repeat addressing; same as the CPU backend.
fn sample(m: Material, uv: vec2<f32>) -> f32 {
    let x = wrap_unit(uv.x) * f32(m.width) - 0.5;
    let y = (1.0 - wrap_unit(uv.y)) * f32(m.height) - 0.5;
    let x0f = floor(x);
    let y0f = floor(y);
    let fx = x - x0f;
    let fy = y - y0f;
    let xs = neighbours(x0f, m.width);
    let ys = neighbours(y0f, m.height);
    let r0 = m.offset + ys.x * m.width;
    let r1 = m.offset + ys.y * m.width;
    let top = texels[r0 + xs.x] + (texels[r0 + xs.y] - texels[r0 + xs.x]) * fx;
    let bottom = texels[r1 + xs.x] + (texels[r1 + xs.y] - texels[r1 + xs.x]) * fx;
    return top + (bottom - top) * fy;
}

@fragment
fn fs_main(f: VertexOut) -> @location(0) vec4<u32> {
    var n = f.normal;
    let len2 = dot(n, n);
    if (len2 > 0.0) {
        n = n * inverseSqrt(len2);
    } else {
        n = -normalize(f.view);
    }
    // Oriented towards the camera (two-sided surfaces).
    if (dot(n, f.view) > 0.0) {
        n = -n;
    }
    var intensity = 0.0;
    if (frame.diffuse.y > 0.5) {
        let m = materials[f.material];
        var albedo = m.albedo;
        if (m.width > 0u) {
            albedo = sample(m, f.uv);
        }
        intensity = albedo * (frame.light.w + frame.diffuse.x * max(dot(n, frame.light.xyz), 0.0));
    }
    let nz_mask = (pack2x16snorm(vec2<f32>(n.z, 0.0)) & 0xffffu) | (instance.mask.x << 16u);
    return vec4<u32>(bitcast<u32>(f.view.z), bitcast<u32>(intensity), pack2x16snorm(n.xy), nz_mask);
}

// Geometry only (no intensity): the same depth, normal and mask with fewer interpolated values. The view ray comes
// from the fragment's pixel and its interpolated depth, which is the same point the full pass interpolates.
struct GeometryOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) z: f32,
    @location(1) normal: vec3<f32>,
}

@vertex
fn vs_geometry(v: VertexIn) -> GeometryOut {
    let full = transform(v);
    var out: GeometryOut;
    out.clip = full.clip;
    out.z = full.view.z;
    out.normal = full.normal;
    return out;
}

@fragment
fn fs_geometry(f: GeometryOut) -> @location(0) vec4<u32> {
    let k = frame.intrinsics;
    // Framebuffer position (u + 0.5, v + 0.5) of pixel (u, v).
    let view = vec3<f32>((f.clip.x - 0.5 - k.z) / k.x, (f.clip.y - 0.5 - k.w) / k.y, 1.0) * f.z;
    var n = f.normal;
    let len2 = dot(n, n);
    if (len2 > 0.0) {
        n = n * inverseSqrt(len2);
    } else {
        n = -normalize(view);
    }
    if (dot(n, view) > 0.0) {
        n = -n;
    }
    let nz_mask = (pack2x16snorm(vec2<f32>(n.z, 0.0)) & 0xffffu) | (instance.mask.x << 16u);
    return vec4<u32>(bitcast<u32>(f.z), 0u, pack2x16snorm(n.xy), nz_mask);
}
