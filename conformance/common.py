"""What the conformance scripts share."""


def verdict(title, compared, failures, min_inputs, noun):
    """Prints the pass/fail count and returns the exit status: 1 when anything failed or
    fewer than min_inputs inputs (named noun) were compared, else 0."""
    print(f"{title}: {compared - failures} passed, {failures} failed")
    if compared < min_inputs:
        print(f"only {compared} {noun} compared, need at least {min_inputs}")
        return 1
    return 1 if failures else 0
