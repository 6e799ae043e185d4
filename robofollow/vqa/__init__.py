"""Scene questions with answers the oracle knows: a probe of a policy's vision-language
backbone, and QA data for co-training."""
