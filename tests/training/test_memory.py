import resource
import sys

import pytest
import torch

from hippo_probe.model.lstm import PeepholeLSTM
from hippo_probe.training.memory import reuse_freed_memory


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc mallopt")
def test_a_training_step_reuses_the_last_steps_activations():
    """Activations above glibc's 32 MiB mmap threshold (here the gates, 66 MB) are page
    faulted in afresh every step by default (~30,000-50,000 faults per step); kept for
    reuse, the third step faults in almost nothing."""
    assert reuse_freed_memory()
    lstm = PeepholeLSTM(9, 128, precision="bf16")
    x = torch.randn(500, 64, 9)

    def faults_of_a_step():
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        h, _ = lstm(x)
        h.sum().backward()
        return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

    first = faults_of_a_step()
    faults_of_a_step()
    assert first > 10_000 and faults_of_a_step() < first / 20
