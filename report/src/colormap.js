// Colour maps of the report: blue (low) - white - red (high), the same ramp
// as the project's PNG renderer, so a Q picture from `curvflow render` and
// the report read alike.

const BLUE = [0.23, 0.3, 0.75];
const WHITE = [0.97, 0.97, 0.97];
const RED = [0.71, 0.02, 0.15];

function mix(a, b, t) {
  return [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t];
}

// t in [0, 1] (clamped) -> [r, g, b] in [0, 1]
export function blueWhiteRed(t) {
  if (!(t > 0)) t = 0; // also NaN
  if (t > 1) t = 1;
  return t < 0.5 ? mix(BLUE, WHITE, 2 * t) : mix(WHITE, RED, 2 * t - 1);
}

export function cssColor(rgb) {
  const c = rgb.map((x) => Math.round(255 * x));
  return `rgb(${c[0]}, ${c[1]}, ${c[2]})`;
}

// CSS linear-gradient of the ramp, for the colour bar.
export function cssGradient() {
  const stops = [];
  for (let i = 0; i <= 10; ++i) stops.push(`${cssColor(blueWhiteRed(i / 10))} ${i * 10}%`);
  return `linear-gradient(to right, ${stops.join(', ')})`;
}

// A symmetric range [-r, r] that holds 98 % of |values| (so a few extreme
// faces do not wash the map out), rounded up to 1, 2 or 5 times a power of
// ten; at least 0.01.
export function robustSymmetricRange(values) {
  const abs = [];
  for (const v of values) if (Number.isFinite(v)) abs.push(Math.abs(v));
  if (abs.length === 0) return 1;
  abs.sort((a, b) => a - b);
  const r = Math.max(abs[Math.min(abs.length - 1, Math.floor(0.98 * abs.length))], 0.01);
  const p = Math.pow(10, Math.floor(Math.log10(r)));
  for (const m of [1, 2, 5, 10]) if (m * p >= r - 1e-12 * p) return m * p;
  return 10 * p;
}
