"""The developer's checks: dependencies (make deps), bit-identity, planted bugs (make test-mutants), sizes, links."""
