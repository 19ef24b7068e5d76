// A live plot of kinetic, potential and total energy over the last
// `window` seconds of simulated time, drawn with the canvas 2-D API.
const SERIES = [
  { key: 'kinetic', label: 'kinetic', colour: '#d04020' },
  { key: 'potential', label: 'potential', colour: '#2060c0' },
  { key: 'total', label: 'total', colour: '#202020' },
];

export class EnergyPlot {
  constructor(canvas, window = 10) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.window = window;
    this.samples = [];
  }

  clear() { this.samples = []; this.draw(); }

  add(time, kinetic, potential) {
    const last = this.samples[this.samples.length - 1];
    if (last && time < last.time) this.samples = []; // reset or reload: time went back
    if (last && time === last.time) return;
    this.samples.push({ time, kinetic, potential, total: kinetic + potential });
    while (this.samples.length > 2 && this.samples[0].time < time - this.window) this.samples.shift();
  }

  draw() {
    const { ctx, canvas } = this;
    const w = canvas.width, h = canvas.height, pad = 4, top = 16;
    ctx.clearRect(0, 0, w, h);
    ctx.fillStyle = '#fafafa';
    ctx.fillRect(0, 0, w, h);
    ctx.font = '10px sans-serif';
    SERIES.forEach((s, k) => { ctx.fillStyle = s.colour; ctx.fillText(s.label, pad + 60 * k, 11); });
    if (this.samples.length < 2) return;
    let lo = Infinity, hi = -Infinity;
    for (const p of this.samples) for (const s of SERIES) { lo = Math.min(lo, p[s.key]); hi = Math.max(hi, p[s.key]); }
    if (hi - lo < 1e-12 * Math.max(1, Math.abs(hi))) { hi += 0.5; lo -= 0.5; }
    const t0 = this.samples[0].time, t1 = this.samples[this.samples.length - 1].time;
    const x = (t) => pad + (w - 2 * pad) * (t1 > t0 ? (t - t0) / (t1 - t0) : 1);
    const y = (e) => h - pad - (h - top - pad) * (e - lo) / (hi - lo);
    ctx.fillStyle = '#666';
    ctx.fillText(`${hi.toPrecision(3)} J`, w - 70, 11);
    ctx.fillText(`${lo.toPrecision(3)} J`, w - 70, h - 6);
    for (const s of SERIES) {
      ctx.strokeStyle = s.colour;
      ctx.beginPath();
      this.samples.forEach((p, i) => (i ? ctx.lineTo : ctx.moveTo).call(ctx, x(p.time), y(p[s.key])));
      ctx.stroke();
    }
  }
}
