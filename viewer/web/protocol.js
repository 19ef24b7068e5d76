// The viewer protocol's binary frame (docs/viewer.md): a 48-byte
// little-endian header, then 3N float32 positions and N float32 speeds.
export const FRAME_MAGIC = 0x46594450; // "PDYF"
export const HEADER_BYTES = 48;

/** Decodes one binary WebSocket message; throws on a malformed one. */
export function decodeFrame(buffer) {
  const view = new DataView(buffer);
  if (buffer.byteLength < HEADER_BYTES || view.getUint32(0, true) !== FRAME_MAGIC) {
    throw new Error(`not a pdyn frame (${buffer.byteLength} bytes)`);
  }
  const count = view.getUint32(24, true);
  if (buffer.byteLength !== HEADER_BYTES + 16 * count) {
    throw new Error(`frame of ${buffer.byteLength} bytes for ${count} particles`);
  }
  return {
    topology: view.getUint32(4, true),
    time: view.getFloat64(8, true),
    step: Number(view.getBigUint64(16, true)),
    count,
    playing: (view.getUint32(28, true) & 1) !== 0,
    kinetic: view.getFloat64(32, true),
    potential: view.getFloat64(40, true),
    positions: new Float32Array(buffer, HEADER_BYTES, 3 * count),
    speeds: new Float32Array(buffer, HEADER_BYTES + 12 * count, count),
  };
}
