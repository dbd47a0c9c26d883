import { defineConfig } from "vite";

// Relative asset paths: the built page works from any folder (output/viewer/, a notebook's
// output directory) served by `python -m http.server`.
export default defineConfig({
  base: "./",
  build: { outDir: "dist", emptyOutDir: true, chunkSizeWarningLimit: 1000 },
});
