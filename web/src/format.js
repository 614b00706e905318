// format.js — the one way the page writes a number for people (counts, areas, volumes,
// coordinates, times, sizes): fmt(x, digits).
//   - an integer of magnitude below 10^15 as it is ("38", "-7", "25000000000");
//   - any other finite number with `digits` significant digits (6 by default), the trailing
//     zeros of its mantissa dropped and its exponent kept ("0.25", "1.465e-10", "2.5e+20",
//     "-3.14159"): what Number() reads back to within half a unit of the last digit;
//   - -0 as "0", NaN as "NaN", the infinities as "∞" and "-∞"; anything not a number as "?".
// (The old page dropped trailing zeros after toPrecision, exponent included: 1.465e-10 read
// "1.46508e-1".)

export function fmt(x, digits = 6) {
  if (typeof x !== 'number') return '?';
  if (Number.isNaN(x)) return 'NaN';
  if (!Number.isFinite(x)) return x > 0 ? '∞' : '-∞';
  if (x === 0) return '0';
  if (Number.isInteger(x) && Math.abs(x) < 1e15) return String(x);
  const d = Math.min(21, Math.max(1, Math.round(digits)));
  const s = x.toPrecision(d);
  const e = s.indexOf('e');
  let m = e < 0 ? s : s.slice(0, e);
  if (m.includes('.')) m = m.replace(/0+$/, '').replace(/\.$/, '');
  if (m === '-0') m = '0';
  return e < 0 ? m : m + s.slice(e);
}
