#include "tendril/render/shaders.h"

namespace tendril::render::shaders {

const char* const kLighting = R"glsl(
const int kMaxLights = 8;
uniform int uLightCount;
uniform vec4 uLightVector[kMaxLights];  // directional: unit vector toward the light, w = 0;
                                        // point: position, w = 1
uniform vec3 uLightColor[kMaxLights];
uniform int uShadowLight;               // index of the light with a shadow map, -1 = none
uniform sampler2D uShadowMoments;
uniform mat4 uShadowFromWorld;          // world -> shadow-map texture coordinates and depth in [0, 1]
uniform vec3 uSkyAmbient;
uniform vec3 uGroundAmbient;
uniform vec3 uCameraPos;
uniform float uExposure;
uniform vec3 uHighlightColor;

// Variance shadow maps (Donnelly & Lauritzen 2006): the blurred map holds E[z] and E[z^2];
// Chebyshev's one-tailed inequality bounds the fraction of the filter region at least as far
// from the light as the receiver, p_max = s^2 / (s^2 + (t - mu)^2).
const float kMinVariance = 2e-6;
// Light-bleeding reduction (Lauritzen, GPU Gems 3 ch. 8): the low tail of p_max is where
// overlapping occluders leak light; remapping [amount, 1] to [0, 1] removes it.
const float kBleedReduction = 0.3;

float shadowVisibility(vec3 worldPos) {
  vec4 s = uShadowFromWorld * vec4(worldPos, 1.0);
  if (any(lessThan(s.xyz, vec3(0.0))) || any(greaterThan(s.xyz, vec3(1.0)))) return 1.0;
  vec2 moments = texture(uShadowMoments, s.xy).rg;
  float t = s.z;
  if (t <= moments.x) return 1.0;
  float variance = max(moments.y - moments.x * moments.x, kMinVariance);
  float d = t - moments.x;
  float pMax = variance / (variance + d * d);
  return clamp((pMax - kBleedReduction) / (1.0 - kBleedReduction), 0.0, 1.0);
}

// Outgoing radiance at P for a surface with unit normal N facing the viewer. Blinn-Phong with
// normalised specular lobes; `translucency` lets light arriving from behind shine through
// (thin leaves).
vec3 shade(vec3 P, vec3 N, vec3 albedo, float specular, float shininess, float translucency) {
  vec3 V = normalize(uCameraPos - P);
  vec3 color = albedo * mix(uGroundAmbient, uSkyAmbient, 0.5 + 0.5 * N.y);
  for (int i = 0; i < uLightCount; ++i) {
    vec3 L;
    vec3 radiance = uLightColor[i];
    if (uLightVector[i].w == 0.0) {
      L = uLightVector[i].xyz;
    } else {
      vec3 d = uLightVector[i].xyz - P;
      float dist2 = max(dot(d, d), 1e-4);
      L = d * inversesqrt(dist2);
      radiance /= 1.0 + dist2;
    }
    float visibility = i == uShadowLight ? shadowVisibility(P) : 1.0;
    float nl = dot(N, L);
    if (nl > 0.0) {
      vec3 H = normalize(L + V);
      float spec = specular * (shininess + 8.0) / 25.132741 * pow(max(dot(N, H), 0.0), shininess);
      color += radiance * (visibility * nl) * (albedo + vec3(spec));
    } else {
      color += radiance * (visibility * -nl * translucency) * albedo;
    }
  }
  return color;
}

// Selected things glow in the highlight colour, brightest at their silhouettes.
vec3 highlight(vec3 color, float amount, vec3 P, vec3 N) {
  if (amount <= 0.0) return color;
  float rim = 1.0 - abs(dot(N, normalize(uCameraPos - P)));
  return mix(color, uHighlightColor, 0.45 * amount) + uHighlightColor * (0.6 * amount * rim * rim);
}

vec3 encodeSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}

// ACES filmic curve (Narkowicz 2015 fit), then sRGB encoding for an 8-bit target.
vec3 toneMap(vec3 c) {
  c *= uExposure;
  return encodeSrgb((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14));
}
)glsl";

const char* const kBranchVertex = R"glsl(
// seed 000 §6: "The branch mesh is dynamically generated [...] on a frame-to-frame basis by
// creating a cylinder mesh between two adjacent particles, where the radius of the particle
// defines the radius of the cylinder. The orientation of two subsequent particles defines a
// reference frame for the start and the end of the cylinder." One instance per node; the
// template vertex id selects the ring (start or end), the angle around it, or a cap vertex
// (caps are a second instanced draw over the few segments that end a chain):
//   [0, n+1)        start ring side vertices (j = 0..n, the seam repeated for the texture)
//   [n+1, 2n+2)     end ring side vertices
//   2n+2, 2n+3      start and end cap apex
//   [2n+4, 3n+4)    start cap rim;  [3n+4, 4n+4) end cap rim
layout(location = 0) in vec4 iStart;      // centre, radius
layout(location = 1) in vec4 iEnd;        // centre, radius
layout(location = 2) in vec4 iStartAxis;  // ring normal, bark v at the start
layout(location = 3) in vec4 iStartRef;   // angle-0 direction, bark v at the end
layout(location = 4) in vec4 iEndAxis;    // ring normal, cap bits (1 start, 2 end)
layout(location = 5) in vec4 iEndRef;     // angle-0 direction, bark layer
layout(location = 6) in vec4 iColor;      // albedo / bark mean, highlight

uniform mat4 uClipFromWorld;
uniform int uSides;

out vec3 vWorld;
out vec3 vNormal;
out vec2 vBarkUv;
flat out vec4 vColor;
flat out float vLayer;

void main() {
  int n = uSides;
  int id = gl_VertexID;
  int ring;
  int j = 0;
  int kind;  // 0 side, 1 cap apex, 2 cap rim
  if (id < 2 * (n + 1)) {
    kind = 0;
    ring = id / (n + 1);
    j = id - ring * (n + 1);
  } else if (id < 2 * n + 4) {
    kind = 1;
    ring = id - (2 * n + 2);
  } else {
    kind = 2;
    int k = id - (2 * n + 4);
    ring = k / n;
    j = k - ring * n;
  }
  vec3 centre = ring == 0 ? iStart.xyz : iEnd.xyz;
  float radius = ring == 0 ? iStart.w : iEnd.w;
  vec3 axis = ring == 0 ? iStartAxis.xyz : iEndAxis.xyz;
  vec3 ref = ring == 0 ? iStartRef.xyz : iEndRef.xyz;
  float angle = 6.2831853 * float(j) / float(n);
  vec3 radial = cos(angle) * ref + sin(angle) * cross(axis, ref);
  vec3 outward = ring == 0 ? -axis : axis;

  vColor = iColor;
  vLayer = iEndRef.w;
  vBarkUv = vec2(float(j) / float(n), ring == 0 ? iStartAxis.w : iStartRef.w);
  vec3 p = centre + radius * radial;
  vec3 normal = radial;
  if (kind != 0) {
    int caps = int(iEndAxis.w + 0.5);
    if ((caps & (ring == 0 ? 1 : 2)) == 0) {
      // No cap here: a degenerate vertex (w = 0 clips the whole triangle away).
      vWorld = centre;
      vNormal = axis;
      gl_Position = vec4(0.0);
      return;
    }
    // A low rounded cone: apex half a radius out, rim normals radial, so the end looks round.
    if (kind == 1) {
      p = centre + 0.5 * radius * outward;
      normal = outward;
    }
  }
  vWorld = p;
  vNormal = normal;
  gl_Position = uClipFromWorld * vec4(p, 1.0);
}
)glsl";

const char* const kBranchFragment = R"glsl(
in vec3 vWorld;
in vec3 vNormal;
in vec2 vBarkUv;
flat in vec4 vColor;
flat in float vLayer;
uniform sampler2DArray uBark;
layout(location = 0) out vec4 fragColor;

void main() {
  vec3 albedo = vColor.rgb * texture(uBark, vec3(vBarkUv, vLayer)).rgb;
  vec3 N = normalize(vNormal);
  vec3 color = shade(vWorld, N, albedo, 0.08, 12.0, 0.0);
  fragColor = vec4(toneMap(highlight(color, vColor.a, vWorld, N)), 1.0);
}
)glsl";

const char* const kLeafVertex = R"glsl(
// seed 000 §6: leaves are points "transformed into curved surfaces" while rendering. One
// instance per leaf: the blade starts at iBase, runs along iAlong and spans ±iHalfWidth. Its
// midline turns about the leaf's X axis by the wind bend angle, reaching it at the tip (as
// mesh/leaf_mesh.h), and its edges are lifted along the normal so the blade is cupped.
// Template vertex id = row * 3 + column (column 0 left edge, 1 midrib, 2 right edge).
layout(location = 0) in vec4 iBase;       // blade start, bend (rad)
layout(location = 1) in vec4 iHalfWidth;  // leaf X * half width, texture layer
layout(location = 2) in vec4 iAlong;      // leaf Y * blade length, highlight
layout(location = 3) in vec4 iTint;

uniform mat4 uClipFromWorld;
uniform int uLeafRows;
uniform float uCup;  // edge lift as a fraction of the half width

out vec3 vWorld;
out vec3 vNormal;
out vec2 vUv;
flat out vec4 vTint;
flat out float vLayer;

void main() {
  int row = gl_VertexID / 3;
  int column = gl_VertexID - 3 * row;
  float t = float(row) / float(uLeafRows);
  float side = float(column - 1);
  float len = length(iAlong.xyz);
  float halfWidth = length(iHalfWidth.xyz);
  vec3 Y = iAlong.xyz / len;
  vec3 X = iHalfWidth.xyz / halfWidth;
  vec3 Z = cross(X, Y);
  float bend = iBase.w;
  float a = bend * t;
  // Arc of constant curvature: the blade keeps its length however far it bends.
  vec3 axial = abs(bend) < 1e-4 ? len * t * Y : len * ((sin(a) / bend) * Y + ((1.0 - cos(a)) / bend) * Z);
  vec3 normal = cos(a) * Z - sin(a) * Y;
  vec3 p = iBase.xyz + axial + side * iHalfWidth.xyz + (uCup * halfWidth * abs(side)) * normal;
  vWorld = p;
  vNormal = normalize(normal - (sign(side) * uCup) * X);
  vUv = vec2(0.5 + 0.5 * side, t);
  vTint = vec4(iTint.rgb, iAlong.w);
  vLayer = iHalfWidth.w;
  gl_Position = uClipFromWorld * vec4(p, 1.0);
}
)glsl";

const char* const kLeafFragment = R"glsl(
in vec3 vWorld;
in vec3 vNormal;
in vec2 vUv;
flat in vec4 vTint;
flat in float vLayer;
uniform sampler2DArray uLeaves;
layout(location = 0) out vec4 fragColor;

void main() {
  // Texture rows run from the image's top (the blade tip) down: v = 0 is the petiole end.
  vec4 tex = texture(uLeaves, vec3(vUv.x, 1.0 - vUv.y, vLayer));
  if (tex.a < 0.5) discard;
  vec3 albedo = tex.rgb * vTint.rgb;
  vec3 N = normalize(vNormal);
  if (!gl_FrontFacing) {
    // The underside: lit from its own side, and paler, as real leaves are.
    N = -N;
    albedo *= vec3(1.15, 1.2, 0.9);
  }
  vec3 color = shade(vWorld, N, albedo, 0.06, 48.0, 0.35);
  fragColor = vec4(toneMap(highlight(color, vTint.a, vWorld, N)), 1.0);
}
)glsl";

const char* const kObstacleVertex = R"glsl(
layout(location = 0) in vec3 aPosition;
uniform mat4 uClipFromWorld;
uniform mat4 uWorldFromLocal;
out vec3 vWorld;

void main() {
  vec4 world = uWorldFromLocal * vec4(aPosition, 1.0);
  vWorld = world.xyz;
  gl_Position = uClipFromWorld * world;
}
)glsl";

const char* const kObstacleFragment = R"glsl(
in vec3 vWorld;
uniform vec3 uColor;
uniform float uSelected;
layout(location = 0) out vec4 fragColor;

void main() {
  // Flat normal of the triangle, facing the viewer (screen x cross screen y points at the eye).
  vec3 N = normalize(cross(dFdx(vWorld), dFdy(vWorld)));
  vec3 color = shade(vWorld, N, uColor, 0.04, 8.0, 0.0);
  fragColor = vec4(toneMap(highlight(color, uSelected, vWorld, N)), 1.0);
}
)glsl";

const char* const kPrimitiveVertex = R"glsl(
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec4 iColumn0;  // worldFromPrimitive, column by column
layout(location = 2) in vec4 iColumn1;
layout(location = 3) in vec4 iColumn2;
layout(location = 4) in vec4 iColumn3;
layout(location = 5) in vec4 iColor;    // rgb, highlight
uniform mat4 uClipFromWorld;
out vec3 vWorld;
flat out vec4 vColor;

void main() {
  vec4 world = mat4(iColumn0, iColumn1, iColumn2, iColumn3) * vec4(aPosition, 1.0);
  vWorld = world.xyz;
  vColor = iColor;
  gl_Position = uClipFromWorld * world;
}
)glsl";

const char* const kPrimitiveFragment = R"glsl(
in vec3 vWorld;
flat in vec4 vColor;
layout(location = 0) out vec4 fragColor;

void main() {
  vec3 N = normalize(cross(dFdx(vWorld), dFdy(vWorld)));
  vec3 color = shade(vWorld, N, vColor.rgb, 0.06, 16.0, 0.0);
  fragColor = vec4(toneMap(highlight(color, vColor.a, vWorld, N)), 1.0);
}
)glsl";

const char* const kStrokeVertex = R"glsl(
layout(location = 0) in vec3 aPosition;    // unit sphere
layout(location = 1) in vec4 iCentre;      // centre, radius
layout(location = 2) in vec4 iColor;
uniform mat4 uClipFromWorld;
out vec3 vWorld;
out vec3 vNormal;
flat out vec3 vColor;

void main() {
  vec3 p = iCentre.xyz + iCentre.w * aPosition;
  vWorld = p;
  vNormal = aPosition;
  vColor = iColor.rgb;
  gl_Position = uClipFromWorld * vec4(p, 1.0);
}
)glsl";

const char* const kStrokeFragment = R"glsl(
in vec3 vWorld;
in vec3 vNormal;
flat in vec3 vColor;
layout(location = 0) out vec4 fragColor;

void main() {
  vec3 N = normalize(vNormal);
  // A little emission keeps painted points readable in shadow.
  vec3 color = shade(vWorld, N, vColor, 0.3, 24.0, 0.0) + 0.3 * vColor;
  fragColor = vec4(toneMap(color), 1.0);
}
)glsl";

const char* const kLineVertex = R"glsl(
// One instance per line, expanded to a screen-space quad uLineWidth pixels wide (core profile
// has no portable wide lines). Lines crossing the eye plane are clipped to just in front of it.
layout(location = 0) in vec4 iStart;
layout(location = 1) in vec4 iEnd;
layout(location = 2) in vec4 iColor;
uniform mat4 uClipFromWorld;
uniform vec2 uViewport;   // framebuffer size (pixels)
uniform float uLineWidth; // pixels
out vec3 vColor;

void main() {
  vColor = iColor.rgb;
  vec4 a = uClipFromWorld * vec4(iStart.xyz, 1.0);
  vec4 b = uClipFromWorld * vec4(iEnd.xyz, 1.0);
  const float kMinW = 1e-4;
  if (a.w < kMinW && b.w < kMinW) {
    gl_Position = vec4(0.0);
    return;
  }
  if (a.w < kMinW) a = mix(a, b, (kMinW - a.w) / (b.w - a.w));
  if (b.w < kMinW) b = mix(b, a, (kMinW - b.w) / (a.w - b.w));
  vec2 halfViewport = 0.5 * uViewport;
  vec2 sa = a.xy / a.w * halfViewport, sb = b.xy / b.w * halfViewport;
  vec2 dir = sb - sa;
  dir = dot(dir, dir) > 1e-12 ? normalize(dir) : vec2(1.0, 0.0);
  vec2 across = vec2(-dir.y, dir.x);
  // Corners: (end, side) for the two triangles of the quad.
  const ivec2 corners[6] = ivec2[](ivec2(0, -1), ivec2(1, -1), ivec2(1, 1), ivec2(0, -1), ivec2(1, 1), ivec2(0, 1));
  ivec2 c = corners[gl_VertexID];
  vec4 p = c.x == 0 ? a : b;
  vec2 offset = 0.5 * uLineWidth * (float(c.y) * across + (c.x == 0 ? -dir : dir));
  p.xy += offset / halfViewport * p.w;
  gl_Position = p;
}
)glsl";

const char* const kLineFragment = R"glsl(
in vec3 vColor;
layout(location = 0) out vec4 fragColor;

vec3 encodeSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}

void main() { fragColor = vec4(encodeSrgb(vColor), 1.0); }
)glsl";

const char* const kMomentsFragment = R"glsl(
#ifdef ALPHA_TEST
in vec2 vUv;
flat in float vLayer;
uniform sampler2DArray uLeaves;
#endif
layout(location = 0) out vec2 moments;

void main() {
#ifdef ALPHA_TEST
  if (texture(uLeaves, vec3(vUv.x, 1.0 - vUv.y, vLayer)).a < 0.5) discard;
#endif
  // Light-space depth is linear (orthographic light). The second moment gets the depth
  // variance across the pixel from its slope (GPU Gems 3 ch. 8), which removes acne on
  // surfaces at grazing angles to the light.
  float z = gl_FragCoord.z;
  float dx = dFdx(z), dy = dFdy(z);
  moments = vec2(z, z * z + 0.25 * (dx * dx + dy * dy));
}
)glsl";

const char* const kFullscreenVertex = R"glsl(
out vec2 vUv;
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  vUv = p;
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)glsl";

const char* const kBlurFragment = R"glsl(
in vec2 vUv;
uniform sampler2D uSource;
uniform vec2 uStep;  // one texel along the blur direction
layout(location = 0) out vec2 result;

void main() {
  // Binomial Gaussian (6 15 20 15 6) / 62 in three fetches: bilinear filtering between texels
  // 1 and 2 returns their weighted mean at offset (1·15 + 2·6) / 21. VSM can pre-filter the
  // map like this, unlike a depth map, which is what makes its shadows soft without aliasing.
  const float kOffset = 27.0 / 21.0;
  const float kCentre = 20.0 / 62.0, kSide = 21.0 / 62.0;
  result = kCentre * texture(uSource, vUv).rg + kSide * texture(uSource, vUv + kOffset * uStep).rg +
           kSide * texture(uSource, vUv - kOffset * uStep).rg;
}
)glsl";

}  // namespace tendril::render::shaders
