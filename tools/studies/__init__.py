"""The validation and method studies: each runs sphseg over its cases and writes docs/data/<study>/."""
