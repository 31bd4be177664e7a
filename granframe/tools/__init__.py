"""Tools built on the run: the command line, benchmarks, advice on resolution, figures, analysis
helpers and the shared pieces of studies."""
