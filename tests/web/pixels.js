// Pixel statistics of a PNG screenshot, for telling a drawn surface from a blank canvas.

import { PNG } from 'pngjs';

/**
 * Fraction of pixels that are clearly colored (max - min channel > 40): the shaded surface, not
 * the white background, the gray box outline or anti-aliasing. Also their mean color.
 */
export function coloredFraction(pngBuffer) {
  const png = PNG.sync.read(pngBuffer);
  const { data, width, height } = png;
  let colored = 0;
  const mean = [0, 0, 0];
  for (let i = 0; i < data.length; i += 4) {
    const [r, g, b] = [data[i], data[i + 1], data[i + 2]];
    if (Math.max(r, g, b) - Math.min(r, g, b) > 40) {
      ++colored;
      mean[0] += r;
      mean[1] += g;
      mean[2] += b;
    }
  }
  const n = Math.max(colored, 1);
  return { fraction: colored / (width * height), mean: mean.map((c) => Math.round(c / n)), width, height };
}

/** Fraction of pixels that differ (any channel by more than 24) between two same-size PNGs. */
export function differingFraction(a, b) {
  const pa = PNG.sync.read(a);
  const pb = PNG.sync.read(b);
  if (pa.width !== pb.width || pa.height !== pb.height) return 1;
  let differing = 0;
  for (let i = 0; i < pa.data.length; i += 4) {
    for (let k = 0; k < 3; ++k) {
      if (Math.abs(pa.data[i + k] - pb.data[i + k]) > 24) {
        ++differing;
        break;
      }
    }
  }
  return differing / (pa.width * pa.height);
}
