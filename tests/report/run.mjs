// Runs browser_test.mjs when Chromium is installed; exits 77 (CTest: skipped) otherwise.
import { existsSync } from 'node:fs';

const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
if (!existsSync(chromium)) {
  console.log(`skipped: no ${chromium} (scripts/install-deps --test installs Debian's chromium)`);
  process.exit(77);
}
await import('./browser_test.mjs');
