// Numbers, sizes and times as the page writes them (one place for every panel).
export const bytesText = (n) => n >= 1 << 20 ? `${(n / (1 << 20)).toFixed(1)} MiB` : n >= 1024 ? `${(n / 1024).toFixed(0)} KiB` : `${n} B`;
export const seconds = (s) => `${s.toFixed(s < 10 ? 1 : 0)} s`;
export const num = (x) => (Math.abs(x) >= 1000 || Math.abs(x) < 0.01) && x !== 0 ? x.toExponential(2) : String(+x.toPrecision(3));
export const count = (n) => n.toLocaleString('en');
export const percent = (f) => `${Math.floor(100 * f)} %`;
