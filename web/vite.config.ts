import { defineConfig } from "vitest/config";

// The designer is served by `tvf serve` from the built files (relative URLs, so any
// mount point works); `npm run dev` proxies the API to a running `tvf serve` on :8080.
export default defineConfig({
  base: "./",
  build: { target: "es2020", chunkSizeWarningLimit: 1500 },
  server: { proxy: { "/api": "http://127.0.0.1:8080" } },
  test: { include: ["test/**/*.test.ts"], environment: "node" },
});
