"""Input and output: JSON and GEXF export, the on-disk roadmap cache,
figures and the ``rpr3-gwr`` command-line tool."""
