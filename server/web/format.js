// Numbers, sizes and times as the page writes them (one place for every panel), and saving a
// file the page holds.
export const bytesText = (n) => n >= 1 << 20 ? `${(n / (1 << 20)).toFixed(1)} MiB` : n >= 1024 ? `${(n / 1024).toFixed(0)} KiB` : `${n} B`;
export const seconds = (s) => `${s.toFixed(s < 10 ? 1 : 0)} s`;
export const num = (x) => (Math.abs(x) >= 1000 || Math.abs(x) < 0.01) && x !== 0 ? x.toExponential(2) : String(+x.toPrecision(3));
export const count = (n) => n.toLocaleString('en');
export const percent = (f) => `${Math.floor(100 * f)} %`;

// Saves a Blob through the browser's download (a link clicked; the URL freed a minute later).
export function saveBlob(blob, name) {
  const a = Object.assign(document.createElement('a'), { href: URL.createObjectURL(blob), download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 60_000);
}
