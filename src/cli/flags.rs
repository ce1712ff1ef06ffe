//! Reading the command line: clap's parser, with two of its answers
//! corrected.
//!
//! - **Suggestions only for near misses.** clap suggests the flag,
//!   command or value most alike by Jaro similarity above 0.7, which is
//!   loose enough that `--exposure` got `--resume` and `--time` got
//!   `--timeline`. Here a suggestion must be within an edit distance (with
//!   transpositions) of a quarter of what was typed, at least one: a
//!   slipped key, a swapped pair, a missing letter, not another word.
//! - **A negative number is a value.** clap reads `--spp -4` as the flag
//!   `--spp` followed by a flag `-4`, and advises `-- -4`. Every option
//!   that takes a value accepts a negative number here, and one that takes
//!   a list of numbers any value beginning with a hyphen (`--crop
//!   -1,0,5,5`), so its own parser sees it, and a count told a number
//!   below its least value says "must be at least N".

use super::Cli;
use clap::error::{ContextKind, ContextValue, ErrorKind};
use clap::{Arg, Args, Command, CommandFactory, FromArgMatches};
use std::any::TypeId;
use std::ffi::OsString;
use strata::scene::RenderOverrides;

/// The command line parsed, or clap's exit: help and version (exit 0), a
/// usage error (exit 2).
pub fn parse() -> Cli {
    parse_from(std::env::args_os()).unwrap_or_else(|e| e.exit())
}

/// [`parse`] of `args` (the program's name first).
pub fn parse_from<T: Into<OsString>>(
    args: impl IntoIterator<Item = T>,
) -> Result<Cli, clap::Error> {
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    let mut cmd = command();
    let matches = cmd
        .try_get_matches_from_mut(&args)
        .map_err(|e| explain(e, &mut cmd, &args))?;
    Cli::from_arg_matches(&matches).map_err(|e| e.format(&mut cmd))
}

/// The `strata` command, every option that takes a value accepting a
/// negative number as one.
pub fn command() -> Command {
    negative_values(Cli::command())
}

fn negative_values(cmd: Command) -> Command {
    cmd.mut_args(|a| {
        if !(a.get_long().is_some() && a.get_action().takes_values()) {
            return a;
        }
        // A list of numbers (`--crop -1,0,5,5`, `--background -1,0,0`) is
        // no number to clap: its value begins with a hyphen however it
        // reads, so that its own parser says what is wrong with it.
        let list = a
            .get_value_names()
            .is_some_and(|names| names.iter().any(|n| n.contains(',')));
        a.allow_negative_numbers(true).allow_hyphen_values(list)
    })
    .mut_subcommands(negative_values)
}

/// clap's error `e` with its suggestions held to near misses, and a
/// number below an option's least value said as such.
fn explain(mut e: clap::Error, cmd: &mut Command, args: &[OsString]) -> clap::Error {
    let sub = subcommand_of(cmd, args);
    match e.kind() {
        ErrorKind::UnknownArgument => {
            let typed = match e.get(ContextKind::InvalidArg) {
                Some(ContextValue::String(arg)) => arg.clone(),
                _ => return e,
            };
            let Some(name) = typed.strip_prefix("--") else {
                return e;
            };
            let name = name.split('=').next().unwrap_or(name);
            let here = match cmd.find_subcommand_mut(&sub) {
                Some(s) => s,
                None => cmd,
            };
            let longs = long_names(here);
            match nearest(name, longs.iter().map(String::as_str)) {
                Some(n) => e.insert(
                    ContextKind::SuggestedArg,
                    ContextValue::String(format!("--{n}")),
                ),
                None => e.remove(ContextKind::SuggestedArg),
            };
            // clap's usage line holds the flag it suggested: the usage
            // of the command as it is instead.
            e.insert(
                ContextKind::Usage,
                ContextValue::StyledStr(here.render_usage()),
            );
            // "'render --threads' exists": a flag of a subcommand, given
            // before it; kept where it is the flag typed or a near miss.
            if let Some(ContextValue::StyledStrs(tips)) = e.get(ContextKind::Suggested) {
                let kept: Vec<_> = tips
                    .iter()
                    .filter(|tip| {
                        let text = tip.to_string();
                        match text.split_once(" --") {
                            Some((_, rest)) => {
                                let flag = rest.split('\'').next().unwrap_or("");
                                nearest(name, [flag]).is_some()
                            }
                            None => true,
                        }
                    })
                    .cloned()
                    .collect();
                if kept.is_empty() {
                    e.remove(ContextKind::Suggested);
                } else {
                    e.insert(ContextKind::Suggested, ContextValue::StyledStrs(kept));
                }
            }
            e
        }
        ErrorKind::InvalidSubcommand => {
            near_only(
                &mut e,
                ContextKind::InvalidSubcommand,
                ContextKind::SuggestedSubcommand,
            );
            e
        }
        ErrorKind::InvalidValue => {
            near_only(
                &mut e,
                ContextKind::InvalidValue,
                ContextKind::SuggestedValue,
            );
            e
        }
        ErrorKind::ValueValidation => below_least(e, cmd, &sub),
        _ => e,
    }
}

/// Drop the suggestions under `suggested` that are not near misses of
/// the value under `typed`.
fn near_only(e: &mut clap::Error, typed: ContextKind, suggested: ContextKind) {
    let Some(ContextValue::String(typed)) = e.get(typed) else {
        return;
    };
    let typed = typed.clone();
    let kept: Vec<String> = match e.get(suggested) {
        Some(ContextValue::String(s)) => vec![s.clone()],
        Some(ContextValue::Strings(s)) => s.clone(),
        _ => return,
    }
    .into_iter()
    .filter(|s| nearest(&typed, [s.as_str()]).is_some())
    .collect();
    if kept.is_empty() {
        e.remove(suggested);
    } else {
        e.insert(suggested, ContextValue::Strings(kept));
    }
}

/// A count given a whole number below its least value (`--spp -4`,
/// `--camera -1`, `--passes 0`): "must be at least N" in place of clap's
/// words for a failed parse; and given something else (`--spp 1.5`):
/// "expected a whole number".
fn below_least(e: clap::Error, cmd: &mut Command, sub: &str) -> clap::Error {
    let (Some(ContextValue::String(flag)), Some(ContextValue::String(value))) = (
        e.get(ContextKind::InvalidArg),
        e.get(ContextKind::InvalidValue),
    ) else {
        return e;
    };
    let (flag, value) = (flag.clone(), value.clone());
    // Not a whole number at all (`1.5`, `ten`): clap says "invalid digit
    // found in string".
    let number = value.trim().parse::<i128>();
    let long = flag.split_whitespace().next().unwrap_or("");
    let here = match cmd.find_subcommand_mut(sub) {
        Some(s) => s,
        None => cmd,
    };
    let Some(arg) = here
        .get_arguments()
        .find(|a| a.get_long().is_some_and(|l| format!("--{l}") == long))
    else {
        return e;
    };
    let Some(least) = least_value(arg) else {
        return e;
    };
    let why = match number {
        Err(_) => "expected a whole number".to_string(),
        Ok(n) if n < least => format!("must be at least {least}"),
        Ok(_) => return e,
    };
    clap::Error::raw(
        ErrorKind::ValueValidation,
        format!("invalid value '{value}' for '{flag}': {why}"),
    )
    .format(here)
}

/// The least value of an option that takes a count (an unsigned integer):
/// 1 where its parser refuses 0 or a render refuses 0 for that setting
/// (`--spp`, `--width`), else 0. `None` for any other option.
fn least_value(arg: &Arg) -> Option<i128> {
    let unsigned = [
        TypeId::of::<u8>(),
        TypeId::of::<u16>(),
        TypeId::of::<u32>(),
        TypeId::of::<u64>(),
        TypeId::of::<usize>(),
    ];
    let parser = arg.get_value_parser();
    if !unsigned.iter().any(|t| parser.type_id() == *t) {
        return None;
    }
    let long = format!("--{}", arg.get_long()?);
    // The option alone (what it requires is no matter here), told 0.
    let probe = Command::new("probe").arg(arg.clone().required(false));
    let parses_zero = probe.try_get_matches_from(["probe", &long, "0"]).is_ok();
    Some(if parses_zero && render_accepts_zero(arg) {
        0
    } else {
        1
    })
}

/// Whether a render takes 0 for the setting of the same name as `arg`
/// (true for an option that is no render setting).
fn render_accepts_zero(arg: &Arg) -> bool {
    let settings = RenderOverrides::augment_args(Command::new("probe"));
    let Some(long) = settings
        .get_arguments()
        .find(|a| a.get_id() == arg.get_id())
        .and_then(Arg::get_long)
        .map(|l| format!("--{l}"))
    else {
        return true;
    };
    settings
        .try_get_matches_from(["probe", &long, "0"])
        .ok()
        .and_then(|m| RenderOverrides::from_arg_matches(&m).ok())
        .is_none_or(|o| o.check().is_ok())
}

/// The subcommand `args` name (the first word that is not a flag), or "".
fn subcommand_of(cmd: &Command, args: &[OsString]) -> String {
    args.iter()
        .skip(1)
        .filter_map(|a| a.to_str())
        .find(|a| !a.starts_with('-'))
        .filter(|a| cmd.find_subcommand(a).is_some())
        .unwrap_or("")
        .to_string()
}

/// Every long flag of `cmd`, `--help` (and the root's `--version`) too.
fn long_names(cmd: &Command) -> Vec<String> {
    let mut names: Vec<String> = cmd
        .get_arguments()
        .filter_map(Arg::get_long)
        .map(str::to_string)
        .collect();
    for name in ["help", "version"] {
        if !names.iter().any(|n| n == name) && (name == "help" || cmd.get_version().is_some()) {
            names.push(name.to_string());
        }
    }
    names
}

/// The candidate nearest to `typed`, if it is a near miss: within an
/// edit distance of a quarter of `typed`'s length, and at least 1.
pub fn nearest<'a>(typed: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (typed.chars().count() / 4).max(1);
    candidates
        .into_iter()
        .map(|c| (edit_distance(typed, c), c))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// Edits (insert, delete, substitute, or swap two neighbours) that turn
/// `a` into `b`: the optimal string alignment distance.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_count_swaps_as_one() {
        assert_eq!(edit_distance("threads", "threads"), 0);
        assert_eq!(edit_distance("treads", "threads"), 1);
        assert_eq!(edit_distance("widht", "width"), 1);
        assert_eq!(edit_distance("", "spp"), 3);
        assert_eq!(edit_distance("time", "timeline"), 4);
    }

    #[test]
    fn only_near_misses_are_suggested() {
        let render = [
            "resume", "timeline", "threads", "spp", "seed", "set", "output",
        ];
        let near = |typed| nearest(typed, render);
        assert_eq!(near("exposure"), None);
        assert_eq!(near("time"), None);
        assert_eq!(near("treads"), Some("threads"));
        assert_eq!(near("sp"), Some("spp"));
        assert_eq!(near("outptu"), Some("output"));
        assert_eq!(near("timelnie"), Some("timeline"));
    }

    fn error(args: &[&str]) -> String {
        let mut all = vec!["strata"];
        all.extend(args);
        match parse_from(all) {
            Ok(_) => panic!("{args:?} parsed"),
            Err(e) => e.render().to_string(),
        }
    }

    #[test]
    fn flags_far_from_any_get_no_suggestion() {
        for (typed, far) in [("--resolve", "--resume"), ("--timelapse", "--timeline")] {
            let text = error(&["render", typed]);
            assert!(!text.contains(far), "{typed}: {text}");
            assert!(text.contains("Usage: strata render [OPTIONS]"), "{text}");
        }
        let text = error(&["render", "--treads", "2"]);
        assert!(
            text.contains("similar argument exists: '--threads'"),
            "{text}"
        );
    }

    #[test]
    fn a_negative_count_is_told_its_least_value() {
        for (args, least) in [
            (&["render", "--spp", "-4"][..], 1),
            (&["render", "x.glb", "--camera", "-1"][..], 0),
            (&["render", "--passes", "0"][..], 1),
            (&["render", "--threads", "-2"][..], 0),
            (&["scaling", "--max-threads", "-1"][..], 1),
        ] {
            let text = error(args);
            assert!(
                text.contains(&format!("must be at least {least}")),
                "{args:?}: {text}"
            );
            assert!(!text.contains("-- -"), "{args:?}: {text}");
        }
        // A number a float or a signed option takes is passed on as it is,
        // and so is a list of numbers beginning with a negative one.
        assert!(parse_from(["strata", "render", "--background", "-1"]).is_ok());
        // (checked where the render reads them, "must be finite and not
        // negative", "pixel coordinates start at 0").
        for (flag, value) in [("--crop", "-1,0,5,5"), ("--background", "-1,0,0")] {
            assert!(
                parse_from(["strata", "render", flag, value]).is_ok(),
                "{flag}"
            );
        }
        // Not a whole number: said so, not "invalid digit found in string".
        for args in [
            &["render", "--spp", "1.5"][..],
            &["render", "--width", "ten"],
            &["render", "--threads", "1.5"],
        ] {
            let text = error(args);
            assert!(text.contains("expected a whole number"), "{args:?}: {text}");
            assert!(!text.contains("invalid digit"), "{args:?}: {text}");
        }
    }

    /// A thread count past any machine's cores is a usage error naming the
    /// flag and the limit, for every command that takes one (unchecked,
    /// `--threads 100000` reserved 32 GB of stacks and never started).
    #[test]
    fn a_thread_count_past_any_machine_is_refused() {
        let max = strata::system::budget::MAX_THREADS;
        for command in [
            &["render"][..],
            &["trace", "m.obj", "--rays", "r", "--hits", "h"],
            &["converge", "s.toml"],
            &["bench"],
        ] {
            let mut args = command.to_vec();
            let too_many = (max + 1).to_string();
            args.extend(["--threads", too_many.as_str()]);
            let text = error(&args);
            assert!(
                text.contains("--threads") && text.contains(&format!("at most {max}")),
                "{args:?}: {text}"
            );
            let mut args = command.to_vec();
            let most = max.to_string();
            args.extend(["--threads", most.as_str()]);
            assert!(
                parse_from(["strata"].into_iter().chain(args)).is_ok(),
                "{command:?}"
            );
        }
        let text = error(&["scaling", "--max-threads", &(max + 1).to_string()]);
        assert!(text.contains("--max-threads"), "{text}");
    }
}
