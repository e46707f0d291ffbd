// The browser tests' small harness: named steps, a failure that says what was expected and what
// was found, and the closing line CTest's log shows ("N passed, N failed").
let passed = 0;
let failed = 0;

export async function step(name, fn) {
  process.stdout.write(`-- ${name}\n`);
  try {
    await fn();
    passed++;
    process.stdout.write(`   ok\n`);
  } catch (e) {
    failed++;
    process.stdout.write(`   FAILED: ${e.stack ?? e}\n`);
    throw e;
  }
}

export function expect(condition, message) {
  if (!condition) throw new Error(message);
}

// Runs a test's body, then always its cleanups, and exits 0 only when every step passed.
export async function run(body) {
  const cleanups = [];
  let error = null;
  try {
    await body((fn) => cleanups.push(fn));
  } catch (e) {
    error = e;
  }
  for (const fn of cleanups.reverse()) {
    try {
      await fn(error);
    } catch (e) {
      process.stdout.write(`cleanup failed: ${e.message}\n`);
    }
  }
  if (error && !failed) process.stdout.write(`FAILED: ${error.stack ?? error}\n`);
  process.stdout.write(`${passed} passed, ${failed || (error ? 1 : 0)} failed\n`);
  process.exit(error ? 1 : 0);
}
