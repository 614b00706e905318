// webfmt.mjs — the unit test of the page's number formatting (web/src/format.js, fmt), run by
// node from tests/t_webfmt.sh: fixed cases (tiny, huge, negative, integers, exponents, the
// values the old page got wrong) and a sweep of many values, each read back by Number()
// within the precision asked for, in the grammar the page promises.
import { fmt } from '../web/src/format.js';

let P = 0, F = 0;
const ok = (n) => { P++; console.log(`ok ${n}`); };
const fail = (n, why) => { F++; console.log(`FAIL ${n}: ${why}`); };
const cases = [
  [1.465e-10, '1.465e-10'], [2.5e10, '25000000000'], [2.5e20, '2.5e+20'], [-2.5e20, '-2.5e+20'],
  [0, '0'], [-0, '0'], [1, '1'], [-7, '-7'], [38, '38'], [0.25, '0.25'], [-0.5, '-0.5'],
  [1 / 3, '0.333333'], [2 / 3, '0.666667'], [89 / 12, '7.41667'], [7 / 12, '0.583333'],
  [1e-7, '1e-7'], [1.5e-7, '1.5e-7'], [-1.465e-10, '-1.465e-10'], [123456.5, '123457'],
  [1234567.5, '1.23457e+6'], [999999.95, '1e+6'], [0.000123, '0.000123'], [1e21, '1e+21'],
  [1e15, '1e+15'], [999999999999999, '999999999999999'], [Number.MAX_VALUE, '1.79769e+308'],
  [Number.MIN_VALUE, '4.94066e-324'], [1.00000001, '1'], [100.5, '100.5'], [12.0001, '12.0001'],
  [NaN, 'NaN'], [Infinity, '∞'], [-Infinity, '-∞'], [undefined, '?'], ['3', '?'], [null, '?'],
];
for (const [x, want] of cases) {
  const got = fmt(x);
  if (got === want) ok(`fmt(${String(x)}) = ${want}`);
  else fail(`fmt(${String(x)})`, `"${got}", wanted "${want}"`);
}
const withDigits = [[1.23456, 3, '1.23'], [0.01, 3, '0.01'], [2.5e-12, 3, '2.5e-12'], [56.04, 3, '56'], [1.05, 2, '1.1']];
for (const [x, d, want] of withDigits) {
  const got = fmt(x, d);
  if (got === want) ok(`fmt(${x}, ${d}) = ${want}`);
  else fail(`fmt(${x}, ${d})`, `"${got}", wanted "${want}"`);
}
// a sweep: magnitudes 1e-320 .. 1e300, both signs, integers and fractions
const grammar = /^-?(0|[1-9]\d*)(\.\d*[1-9])?(e[+-][1-9]\d*)?$/;
let n = 0, bad = [];
let seed = 12345;
const rnd = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648);
for (let e = -320; e <= 300; e += 1) {
  for (let k = 0; k < 6; k++) {
    const mant = 1 + 9 * rnd();
    for (const s of [1, -1]) {
      const x = s * mant * 10 ** e;
      if (!Number.isFinite(x) || x === 0) continue;
      const t = fmt(x);
      n++;
      const back = Number(t);
      const tol = Math.abs(x) < 1e-300 ? Math.abs(x) * 1e-2 + 5e-324 : Math.abs(x) * 5.0001e-6;
      if (!grammar.test(t) || !(Math.abs(back - x) <= tol) || Math.sign(back) !== s) bad.push(`${x} -> ${t}`);
      if (/e/.test(t) && !/e[+-]\d+$/.test(t)) bad.push(`${x} -> ${t}: exponent lost`);
    }
  }
}
for (let i = -2000; i <= 2000; i += 7) {
  const t = fmt(i * 1234567);
  n++;
  if (t !== String(i * 1234567)) bad.push(`${i * 1234567} -> ${t}`);
}
if (bad.length) fail(`${n} swept values read back within 6 digits, in the grammar`, bad.slice(0, 5).join('; '));
else ok(`${n} swept values read back within 6 digits, in the grammar`);
console.log(`${P} passed, ${F} failed`);
process.exit(F ? 1 : 0);
