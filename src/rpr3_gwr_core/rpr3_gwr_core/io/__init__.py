"""Input and output: JSON and GEXF export, the on-disk roadmap cache,
mechanism and scene files and the ``rpr3-gwr`` command-line tool."""
