//! bench (being written).
/// Entry point of the matching `pfe` subcommand; parses its own arguments.
pub fn cli(args: &[String]) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet (args: {args:?})")
}
