"""The asv suite of masonrydam (asv.conf.json at the repository root): short, repeatable figures of the costs
of start-up and of a time step, kept per commit. The scripts beside this folder (benchmarks/*.py) measure the
long cases."""
